"""Learn: the paper's peephole LSTM and its compiled time loops, training and evaluation, frame-by-frame
streaming, and a physics baseline without a network."""
