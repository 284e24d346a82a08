"""left_general_margin.py without the prior that holds the residual to the planner (prior_kl 0): with the prior, the
residual's mean stayed within 1e-5 of a half range (prior KL 0.005 per state at 9.8e7 samples) and the margin reward
did not rise, so the hand played as the planner with a micro-offset (results/general_left/session34/). Without it,
does the margins' gradient move the mean somewhere useful, or does it drift as the scaled residuals did?

Measured (results/general_left/session34/, one H100, 4.7e7 samples in 7.5 minutes): it drifts downhill. The training
reward fell from 1.62 to 1.52 per string and step, F1 on the training windows from 0.68 to 0.64, and the hand played
0.664 on 48 held-out songs (the planner with offsets: 0.772) and 0.947 on the official ones (0.987).

    dexguitar train --hand left --style general --procedural 128 --config experiments/left_general_margin_free.py \\
        --out runs/left-general-margin-free --max-minutes 7.5
"""
import dataclasses
import os
import runpy

_margin = runpy.run_path(os.path.join(os.path.dirname(__file__), "left_general_margin.py"))
CONFIG = dataclasses.replace(_margin["CONFIG"], prior_kl=0.0)
ENV = _margin["ENV"]
