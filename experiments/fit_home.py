"""Find the home poses in dexguitar.world.scene.HOME by least squares on fingertip / pick targets.

Run: python experiments/fit_home.py   (prints the two 27-vectors to paste into scene.HOME)
"""
import mujoco
import numpy as np
from scipy.optimize import least_squares

from dexguitar.world import hands as H
from dexguitar.world import scene as S
from dexguitar.world.guitar import GUITAR as G


def site(m, d, name):
    return d.site_xpos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_SITE, name)]


def body(m, d, name):
    return d.xpos[mujoco.mj_name2id(m, mujoco.mjtObj.mjOBJ_BODY, name)]


def gap(a0, a1, b0, b1):
    """Approximate closest distance between two segments (sampled), enough for a pose fit."""
    t = np.linspace(0, 1, 12)[:, None]
    pa, pb = a0 + t * (a1 - a0), b0 + t * (b1 - b0)
    return np.sqrt(((pa[:, None] - pb[None]) ** 2).sum(-1)).min()


def fit(role, guess, residual_terms):
    m = S.build_model(role)
    d = mujoco.MjData(m)
    gpos, grot = S.guitar_pose(m)
    lo = np.array([j.range[0] for j in H.joints(role)])
    hi = np.array([j.range[1] for j in H.joints(role)])

    def to_guitar(p):
        return grot.T @ (p - gpos)

    def residual(q):
        d.qpos[:] = q
        mujoco.mj_kinematics(m, d)
        return np.concatenate(residual_terms(lambda n: to_guitar(site(m, d, S.PREFIX[role] + n)),
                                             lambda n: to_guitar(body(m, d, S.PREFIX[role] + n)), q))

    sol = least_squares(residual, np.clip(guess, lo + 1e-6, hi - 1e-6), bounds=(lo, hi), max_nfev=4000)
    return sol.x, sol.cost


def left_terms(site_g, body_g, q):
    out = []
    for f, fret in zip(H.FINGERS, (5, 6, 7, 8)):
        tgt = G.target_points[2, fret].copy()       # over string 3
        tgt[2] = G.string_z + 0.012                  # hovering 12 mm above the string
        out.append(10 * (site_g(f + "_tip") - tgt))
    thumb = np.array([-0.008, (G.fret_y[5] + G.fret_y[6]) / 2 + 0.01, -0.02])  # behind the neck
    out.append(10 * (site_g("thumb_tip") - thumb))
    for f in H.FINGERS:                                # knuckles beside the treble edge, clear of the neck
        k = body_g(f + "1")
        out.append(10 * np.array([max(0.0, 0.045 - k[0])]))
    out.append(0.02 * (q[6:] - np.array([0.3, -0.8, 0.8, 0.6, 0.4] + [0.6, 0.0, 1.0, 0.6] * 4)))
    return out


def right_terms(site_g, body_g, q):
    out = []
    pick = np.array([0.0, -0.33, G.string_z + 0.008])   # above strings 3/4 over the soundhole
    out.append(10 * (site_g("pick") - pick))
    out.append(3 * (site_g("thumb_tip") - (pick + [0.0, 0.0, 0.012])))  # thumb pad near the pick
    for f in ("middle", "ring", "pinky"):              # curled fingers clear of the strings
        out.append(10 * np.array([max(0.0, G.string_z + 0.02 - site_g(f + "_tip")[2])]))
    thumb = (body_g("thumb3"), site_g("thumb_tip"))    # thumb and index capsules touch, not overlap
    for a, b in ((body_g("index2"), body_g("index3")), (body_g("index3"), site_g("index_tip"))):
        out.append(20 * np.array([max(0.0, 0.0135 - gap(*thumb, a, b))]))
    for b in H.KEY_LINKS:                              # the whole hand above the guitar top, wrist well above
        clearance = 0.06 if b == "wrist" else 0.015
        out.append(10 * np.array([max(0.0, G.string_z + clearance - body_g(b)[2])]))
    out.append(0.02 * (q[6:] - np.array([0.3, 0.8, -0.8, -0.6, -0.4] + [0.6, 0.0, 1.5, 0.6] + [1.0, 0.0, 1.2, 0.8] * 3)))
    return out


if __name__ == "__main__":
    np.set_printoptions(precision=4, suppress=True, linewidth=150)
    lguess = np.zeros(27)
    lguess[:6] = [0.1, 0.08, 0.0, -1.57, 0.0, -1.57]
    lguess[6:] = [0.3, -0.8, 0.8, 0.6, 0.4] + [0.6, 0.0, 1.0, 0.6] * 4
    rguess = np.zeros(27)
    rguess[:6] = [0.0, -0.3, 0.09, 0.0, 0.0, 1.57]
    rguess[6:] = [0.3, 0.8, -0.8, -0.6, -0.4] + [0.6, 0.0, 1.5, 0.6] + [1.0, 0.0, 1.2, 0.8] * 3
    for role, guess, terms in (("left", lguess, left_terms), ("right", rguess, right_terms)):
        best = None
        rng = np.random.default_rng(0)
        for trial in range(12):
            g = guess.copy()
            if trial:
                g[3:6] += rng.normal(0, 0.8, 3)
            q, cost = fit(role, g, terms)
            if best is None or cost < best[1]:
                best = (q, cost)
        print(role, "cost", best[1])
        print(repr(np.round(best[0], 4)))
