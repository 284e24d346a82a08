"""The IK planner's plans do not depend on rounding, so that CPUs with other floating-point paths (BLAS kernels, thread
counts, fused multiply-adds in MuJoCo) plan the same: its IK solves run to convergence (`planner.tracking.converge`), and neither
the tracker nor the simulated trials amplify a rounding-sized difference into another decision. Shown on one CPU:
relative perturbations of 1e-13, about what other rounding leaves after a solve, injected into the IK's starts and
solutions and into the tracker's rollouts, change no decision and move the motion by far less than a millimetre."""
from types import SimpleNamespace

import numpy as np

from dexguitar import planner as P
from dexguitar.planner import left as L
from dexguitar.planner import tracking as T
from test_scripted import SONATA_BARRE

NOISE = 1e-13


def decisions(notes: P.Notes):
    """(the discrete plan, the continuous one) of the latest left planner and of the right planner waiting for it:
    per note hand position and fingering, the frets detected after every tracked step and the first step that holds
    each note, the right hand's strokes; the desired and the tracked joint values."""
    left = P.ScriptedLeft()
    desired = left.desired(notes)
    _, q = P.Tracker("left").track(desired)
    timing = left.timing(notes, q)
    strokes = P.ScriptedRight().sweeps(notes, timing)[0]
    return (left.plans(notes), timing.ready.tolist(), timing.press.tolist(), strokes), (desired, q)


def perturb(monkeypatch, seed: int) -> None:
    """From here on (until `monkeypatch` undoes it) every IK solve starts from and returns values off by a relative
    NOISE, and so does every control the tracker's rollouts try; nothing solved before is reused."""
    rng = np.random.default_rng(seed)
    off = lambda x: np.asarray(x) * (1 + NOISE * rng.standard_normal(np.shape(x)))   # noqa: E731
    fit, least_squares, rollout = L.converge, L.least_squares, T.rollout.rollout
    monkeypatch.setattr(L, "_SOLVED", {})
    monkeypatch.setattr(L, "converge", lambda residual, x0, *a, **k: off(fit(residual, off(x0), *a, **k)))
    monkeypatch.setattr(L, "least_squares", lambda fun, x0, **k: least_squares(fun, off(x0), **k))
    monkeypatch.setattr(T, "rollout", SimpleNamespace(
        rollout=lambda models, data, state, control, **k: rollout(models, data, state, off(control), **k)))


def test_rounding_sized_perturbations_change_no_decision(monkeypatch):
    """`SONATA_BARRE`: a barre chosen over fingerings that do not hold, and the ring finger across two strings chosen
    above it, by trials in simulation. An IK stopped at a relative cost tolerance put two CPUs' barre hands 0.2 rad
    apart, `1 x x 3 3 1` held on one of them only, and these perturbations moved the motion by more than 1 rad;
    solved to convergence, they move it by about 1e-7."""
    plan, (desired, q) = decisions(SONATA_BARRE)
    assert plan[0][0][3] == (L.BARRE_POSITIONS + 1, {0: (L.BARRE, 1), 2: (L.PAIR + 1, 3)})
    for seed in (1, 2):
        with monkeypatch.context() as m:
            perturb(m, seed)
            again, (desired_again, q_again) = decisions(SONATA_BARRE)
        assert again == plan
        assert np.abs(desired_again - desired).max() < 1e-5 and np.abs(q_again - q).max() < 1e-5     # rad and m
