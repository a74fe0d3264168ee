"""Methods two or more chapters share: the learners and how they are scored, the camera conditions, the
tracker and its error model, the rendered videos, the exact ceilings, MiniRocket's cached fits and the
decision's operating points. No module here imports a chapter."""
