#!/usr/bin/python3
"""Fig. 3: internal adversity (DTW, a) and external adversity (familiarity of the connector's states, b-c).

<<<<<<< HEAD
    /usr/bin/python3 postprocess/fig3.py RUN.h5 [--out DIR] [--dpi 150] [--env wind] [--replicate 0]
                                              [--boot 1000] [--boot-seed 0]

Reads /analysis of a divcoll run file (src/stages/analysis.hpp) and writes DIR/fig3_adversity_familiarity.png
and .pdf (DIR defaults to out/figures). Two connector types, both weak and deployed as trained: uniform-trained
on clones (orange, hatched, dashed outline, as in fig2.py) and diverse-trained on diverse pairs (blue, solid).

(a) How much a tethered agent's behaviour differs from the same agent's independent behaviour in the same
    environment: DTW distance per step (masses relative to the centre of mass, u), pooled over the flat and
    the novel environments and every pair of a connector replicate, then averaged over replicates. Worse /
    better agent = the one that travelled less / more alone. The worse and better bars, their error bars
    (95% percentile bootstrap CI over the replicate means) and the stars (Welch's t-test, uniform vs
    diverse: *** p < 0.001, ** < 0.01, * < 0.05, n.s.) are the numbers the C++ analysis stage stored
    (adversity/summary, adversity/welch). The "all agents" bars (the paper's large bars) are computed here
    from adversity/<type>/dtw, both slots pooled, with the same kind of CI (--boot resamples, --boot-seed)
    and Welch test. Grey dots: the replicate means.
(b, c) One PaCMAP fit of the connector's hidden states in flat (training) and in one novel environment (--env,
    default wind; the first novel environment done when it is absent), replicate --replicate, for the
    uniform-trained (b) and the diverse-trained (c) connector. Coordinates are rounded half to even
    (numpy.round) into unit cells; each state falls in a cell holding both training and novel states, only
    training or only novel states. Each fit is drawn as three panels, one per class, with the class's count
    of states and cells in the title: every state in light grey, the class's states on top in colour
    (training circles, novel crosses), so the few training-only and novel-only states (tens among
    thousands) are visible. The classification is recomputed here from the embedding and n_states and
    checked against the stored counts (a mismatch is printed and written on the panel).

Exit status: 0 done; 2 the file is not a divcoll run file, has no analysis stage, or lacks the datasets the
figure needs (message on stderr). An analysis stage that is not complete is drawn from what is there, with a
warning.
"""

from __future__ import annotations

=======
The command line of divcoll_post.figures.fig3 (`--help` for its arguments)."""
>>>>>>> py
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from divcoll_post.figures.fig3 import main  # noqa: E402

if __name__ == "__main__":
    sys.exit(main())
