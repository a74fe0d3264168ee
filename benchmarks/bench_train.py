"""Training speed of the paper's peephole LSTM against nn.LSTM of the same size, in one run.

Both are the full classifier of ``study.learn.model`` (2 layers x 64 units, dropout, linear head) on
random inputs of shape (B, T, 3); one training step is forward + backward (full BPTT) + Adam. Prints,
for T = 90 and 300 frames: ms per step, sequences per second, the time of one epoch of the paper's
training set (1600 sequences), and the peephole/nn.LSTM throughput ratio (1.0 = as fast as the
vendor kernel). On CPU a third row, ``peephole-pt``,
times the same layer with its time loop as PyTorch operations instead of the compiled loop of
``study.learn.native`` (the plain baseline of that kernel), and two more the GRU of the ablation: ``gru`` on
its compiled loop (:mod:`study.learn.gru`), ``gru-pt`` as plain ``nn.GRU``; and ``peephole-ng``, the
compiled loop without the finiteness check that guards its entry (``native.all_finite``), to show what
that check costs. Also the streaming cost: one
frame's update of a single trajectory's state. Batch 32 as well on CPU (the training default). On
CUDA too when a GPU is present (batch 128 and 1024).

    python benchmarks/bench_train.py [--quick] [--threads N] [--device cpu|cuda|all]
"""

from __future__ import annotations

import argparse
import contextlib
import time

import numpy as np
import torch
import torch.nn.functional as F

from study.learn import native
from study.learn.model import Classifier
from study.learn.stream import Streamer

EPOCH_SEQUENCES = 1600
"""Training sequences per epoch at paper scale (2000 train trajectories minus a 20 % validation part)."""


def _sync(device: str) -> None:
    if device == "cuda":
        torch.cuda.synchronize()


@contextlib.contextmanager
def unguarded():
    """The compiled loops entered without checking that every number is finite (benchmark only)."""
    check = native.all_finite
    native.all_finite = lambda *tensors: True
    try:
        yield
    finally:
        native.all_finite = check


def _mode(cell: str) -> contextlib.AbstractContextManager:
    return native.disabled() if cell.endswith("-pt") else unguarded() if cell.endswith("-ng") else contextlib.nullcontext()


def time_steps(cells: tuple[str, ...], B: int, T: int, steps: int, device: str) -> dict[str, float]:
    """Seconds per training step of each cell's classifier: median of ``steps`` after one warm-up step.

    The cells' steps are interleaved (one of each in turn), so a slow spell of this shared machine
    hits them alike and their ratio stays meaningful.
    """
    x = torch.randn(B, T, 3, device=device)
    y = torch.randint(0, 2, (B,), device=device)
    nets = {}
    for cell in cells:
        torch.manual_seed(0)
        net = Classifier(3, hidden=64, layers=2, dropout=0.2, cell=cell.removesuffix("-pt").removesuffix("-ng")).to(device).train()
        nets[cell] = (net, torch.optim.Adam(net.parameters(), lr=1e-3))
    times: dict[str, list[float]] = {c: [] for c in cells}
    for i in range(steps + 1):
        for cell, (net, opt) in nets.items():
            _sync(device)
            t0 = time.perf_counter()
            with _mode(cell):
                loss = F.cross_entropy(net(x), y)
                opt.zero_grad(set_to_none=True)
                loss.backward()
                opt.step()
            _sync(device)
            if i:
                times[cell].append(time.perf_counter() - t0)
    return {c: sorted(t)[len(t) // 2] for c, t in times.items()}


@torch.no_grad()
def time_stream(cell: str, frames: int) -> float:
    """Seconds per streamed frame of one trajectory (CPU, eval mode)."""
    torch.manual_seed(0)
    net = Classifier(3, cell=cell).eval()
    state = net.init_state(1)
    xs = torch.randn(frames, 1, 3)
    for x_t in xs[:10]:
        net.step(x_t, state)
    t0 = time.perf_counter()
    for x_t in xs:
        _, state = net.step(x_t, state)
    return (time.perf_counter() - t0) / frames


def time_streamer(frames: int, repeats: int = 5) -> float:
    """Seconds per streamed frame of one trajectory with the NumPy :class:`study.learn.stream.Streamer`
    (best of ``repeats`` passes over ``frames`` frames, returning class probabilities every frame)."""
    torch.manual_seed(0)
    s = Streamer(Classifier(3).eval())
    xs = np.random.default_rng(0).normal(size=(frames, 3)).astype(np.float32)
    for x_t in xs[:10]:
        s.push(x_t)
    best = float("inf")
    for _ in range(repeats):
        s.reset()
        t0 = time.perf_counter()
        for x_t in xs:
            s.push(x_t)
        best = min(best, (time.perf_counter() - t0) / frames)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--quick", action="store_true", help="fewer timed steps (3 instead of 9), T = 90 only on CPU")
    ap.add_argument("--threads", type=int, default=1, help="CPU threads, the same for both models (default: 1, as training uses)")
    ap.add_argument("--device", choices=["cpu", "cuda", "all"], default="all",
                    help="where to measure; 'all' = CPU, and CUDA when available (default: all)")
    a = ap.parse_args()
    torch.set_num_threads(a.threads)
    devices = ["cpu"] if a.device == "cpu" else ["cuda"] if a.device == "cuda" else ["cpu", "cuda"]
    devices = [d for d in devices if d == "cpu" or torch.cuda.is_available()]
    steps = 3 if a.quick else 9
    print(f"torch {torch.__version__}, {a.threads} CPU thread(s); 2 x 64 classifier, full BPTT, Adam")
    print(f"peephole backend: {native.backend()} (peephole-pt: the same layer as PyTorch operations, the plain baseline)")
    print(f"{'device':6} {'B':>5} {'T':>4} {'cell':11} {'ms/step':>9} {'seq/s':>9} {'epoch s':>8} {'ratio':>6}")
    for device in devices:
        # batch 32 too: the training defaults' batch, where the per-step overhead of eager ops dominates
        shapes = [(128, 90)] if (a.quick and device == "cpu") else [(128, 90), (128, 300), (32, 90)]
        if device == "cuda":
            shapes += [(1024, 90), (1024, 300)]
        for B, T in shapes:
            compiled = device == "cpu" and native.active() is not None
            cells = ("torch-lstm", "peephole", "peephole-ng", "peephole-pt", "gru", "gru-pt") if compiled else ("torch-lstm", "peephole")
            res = time_steps(cells, B, T, steps if device == "cpu" else 10, device)
            for cell, s in res.items():
                ratio = res["torch-lstm"] / s
                print(f"{device:6} {B:5d} {T:4d} {cell:11} {s * 1e3:9.1f} {B / s:9.0f} "
                      f"{EPOCH_SEQUENCES / B * s:8.2f} {ratio:6.2f}")
            if compiled:
                print(f"{'':17} compiled GRU vs nn.GRU: {res['gru-pt'] / res['gru']:.2f}x; "
                      f"finiteness check: peephole {res['peephole'] / res['peephole-ng']:.3f}x the unchecked step")
    frames = 300 if a.quick else 2000
    stream = {c: time_stream(c, frames) for c in ("torch-lstm", "peephole")}
    fast = time_streamer(frames)
    print(f"streaming, one trajectory, CPU, Classifier.step (PyTorch): nn.LSTM {stream['torch-lstm'] * 1e6:.0f} us/frame, "
          f"peephole {stream['peephole'] * 1e6:.0f} us/frame")
    print(f"streaming, one trajectory, CPU, study.stream.Streamer (NumPy), peephole: {fast * 1e6:.1f} us/frame "
          f"(target < 50 us; {stream['peephole'] / fast:.1f}x Classifier.step)")


if __name__ == "__main__":
    main()
