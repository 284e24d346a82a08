"""The picking hand's planner: the pick sweeps from the gap before each note's first target string to the gap after
its last, 3 mm below string height, lifted 4 mm over a string it passes without picking; the directions are chosen
over the whole song (alternate picking on one string, a sweep on to the next). In the duet each stroke waits for the
simulated left hand to hold its note (`LeftTiming`), since the strict both-hands rule counts earlier picks as wrong.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from dexguitar.planner.tracking import Notes, min_jerk
from dexguitar.world.kinematics import HandKinematics
from dexguitar.world import scoring
from dexguitar.world.guitar import GUITAR, N_STRINGS


RIGHT_PLANNER_VERSION = 4


@dataclasses.dataclass
class LeftTiming:
    """What the right hand's planner knows of the tracked left plan in the duet: per note the first control step that
    ends with the note held (`ready`), and the frets the env detects after every step (`press`, (T, 6))."""

    ready: np.ndarray
    press: np.ndarray

    def lasts(self, goal, s: int, step: int, frames: int) -> bool:
        """Does string s stay as `goal` asks (the note's left goal) for `frames` steps from `step` on? A pick's hold
        (the duet's rule (3), `scoring`) may run on into the next notes while the string stays so."""
        run = self.press[step:step + frames]
        return len(run) == frames and bool(np.all(np.asarray(scoring.left_ok(run, np.asarray(goal)))[:, s]))


@dataclasses.dataclass
class Sweep:
    """One note's stroke: the pick moves from `start` to `end` (string coordinates: string i, 0-based,
    at i; the gaps at i +- 0.5) in `frames` control steps, crossing its first string at step `cross` (a fraction
    `tau` of the way)."""

    note: int
    start: float
    end: float
    cross: float
    tau: float
    frames: float
    strings: int
    note_end: int

    @property
    def t0(self) -> float:
        return self.cross - self.tau * self.frames

    @property
    def t1(self) -> float:
        return self.t0 + self.frames


class ScriptedRight:
    """The picking hand: the pick point follows strokes across the target strings (`sweeps`), found by damped least
    squares on the wrist (slides penalised: they are slow) with the fingers kept in the home grip. In the duet a
    stroke waits for the simulated left hand and is fitted to its presses (`fit`). `early_gap`: in
    `flight_of_the_bumblebee1`'s 5-frame lines a crossing moved into step 0 after a 5-frame note would leave that note
    a stroke too short (2.7 frames, 4 steps between crossings) for the simulated pick to cross its string: 4 such
    notes missed."""

    depth = 0.003          # stroke bottom below string height (training needs >= 1 mm, evaluation > 0)
    lift = 0.004           # above string height while passing over a string that is not picked
    sweep_cross = 1        # a note's (first) string is crossed during this step of the note at the earliest ...
    ready_lag = 0          # ... and in the duet this many steps after the first step that ends with the note held
    sweep_frames = 8.0     # the longest stroke over one string, gap to gap; +`sweep_extra` per extra string: a strum
    sweep_extra = -0.5     # is quicker, so that its last string is picked early enough to be held 2/3 of the note
    half_min = 1.0         # a stroke takes at least this long on either side of its crossing
    travel_min = 1.5       # a travel between strokes takes at least this long ...
    travel_rate = 1.2      # ... and this many steps per string spacing (the simulated pick follows ~1 per step)
    spare = 1.0            # what a travel leaves free around it before its crossing is moved later
    max_delay = 2.0        # the most a crossing moves later in its note
    lift_cost = 1.0        # `directions`: a string passed over costs as much as moving one spacing more
    # the duet (`fit`)
    strum_rate = 0.9       # a stroke quickened for the holds takes at least this many steps per string
    pick_lag = 0.4         # the simulated pick crosses a string up to this many steps after the plan does
    early_cross = 0.5      # where that holds more strings, a note's first string is crossed this late in its step 0
    early_gap = 4.5        # ... only where the stroke before crossed its first string at least this many steps before

    def __init__(self):
        self.guitar = GUITAR
        self.kin = HandKinematics("right")
        self.kin.set(self.kin.home)
        self.pick0 = self.kin.site(self.kin.hand.pick)
        self.y = self.pick0[1]
        sign = self.guitar.sign
        self.xs = np.array([self.guitar.string_x(i + 1, self.y) for i in range(N_STRINGS)])
        gap = np.abs(np.diff(self.xs)).mean()
        # gaps: g[0] beyond string 1, g[i] between strings i and i+1 (0-based i-1, i), g[6] beyond string 6
        self.gaps = np.concatenate([[self.xs[0] + sign * gap / 2], (self.xs[:-1] + self.xs[1:]) / 2,
                                    [self.xs[-1] - sign * gap / 2]])
        self.active = np.arange(6)                       # wrist slides and hinges move, fingers hold the pick
        self.weights = np.array([0.03, 0.03, 0.03, 0.001, 0.001, 0.001])   # per m, per rad
        # string coordinates: sigma -0.5, 0, 0.5, ..., 5.5 at the gaps and strings
        self._sig = np.arange(-0.5, N_STRINGS, 0.5)
        self._x = np.array([self.gaps[int(s + 0.5)] if s % 1 else self.xs[int(s)] for s in self._sig])

    # --- the pick path: sweeps
    def x_of(self, sigma):
        """Guitar-frame x of string coordinates (linear beyond the outer gaps)."""
        s = np.asarray(sigma, float)
        lo = self._x[0] + (s - self._sig[0]) * (self._x[1] - self._x[0]) / 0.5
        hi = self._x[-1] + (s - self._sig[-1]) * (self._x[-1] - self._x[-2]) / 0.5
        return np.where(s < self._sig[0], lo, np.where(s > self._sig[-1], hi, np.interp(s, self._sig, self._x)))

    def sigma_of(self, x: float) -> float:
        """The string coordinate of a guitar-frame x (inverse of `x_of`)."""
        order = np.argsort(self._x)
        xp, sp = self._x[order], self._sig[order]
        slope = (sp[-1] - sp[0]) / (xp[-1] - xp[0])
        if x < xp[0]:
            return float(sp[0] + (x - xp[0]) * slope)
        if x > xp[-1]:
            return float(sp[-1] + (x - xp[-1]) * slope)
        return float(np.interp(x, xp, sp))

    @staticmethod
    def stroke_ends(a: int, b: int, down: bool) -> tuple[float, float]:
        """(start, end) of a stroke over strings a..b (0-based, a nearer string 1): down goes toward string 1."""
        return (b + 0.5, a - 0.5) if down else (a - 0.5, b + 0.5)

    def _travel_frames(self, s0: float, s1: float) -> float:
        dist = abs(s1 - s0)
        return 0.0 if dist < 1e-6 else max(self.travel_min, self.travel_rate * dist)

    def directions(self, notes_ab, crosses, sigma0: float) -> list[bool]:
        """Per stroke, down (True) or up: the least total of travel plus `lift_cost` per string passed over, each
        travel per frame of the time it has (dynamic programming over the two directions of every stroke)."""
        def cost(s0, s1, dt):
            passed = sum(1 for k in range(N_STRINGS) if min(s0, s1) < k < max(s0, s1))
            return (abs(s1 - s0) + self.lift_cost * passed) / max(dt, 1.0)
        n = len(notes_ab)
        if n == 0:
            return []
        dirs = (True, False)
        total = np.array([cost(sigma0, self.stroke_ends(*notes_ab[0], d)[0], crosses[0]) for d in dirs])
        back = np.zeros((n, 2), int)
        for k in range(1, n):
            dt = crosses[k] - crosses[k - 1]
            new = np.empty(2)
            for j, d in enumerate(dirs):
                start = self.stroke_ends(*notes_ab[k], d)[0]
                c = [total[i] + cost(self.stroke_ends(*notes_ab[k - 1], dd)[1], start, dt) for i, dd in enumerate(dirs)]
                back[k, j] = int(np.argmin(c))
                new[j] = min(c)
            total = new
        j = int(np.argmin(total))
        out = [True] * n
        for k in range(n - 1, -1, -1):
            out[k] = dirs[j]
            j = back[k, j]
        return out

    def sweeps(self, notes: Notes, earliest=None) -> tuple[list[Sweep], float]:
        """The strokes and the string coordinate of the home pick. earliest: None (alone), each note's first step at
        which its strings may be crossed, or a `LeftTiming` (the duet)."""
        timing = earliest if isinstance(earliest, LeftTiming) else None
        earliest = timing.ready if timing is not None else earliest
        sigma0 = self.sigma_of(self.pick0[0])
        rows = []
        for i in range(notes.n):
            tg = np.flatnonzero(notes.pick[i])
            if len(tg) == 0:
                continue
            step = notes.onset[i] + self.sweep_cross
            if earliest is not None:
                step = max(step, int(earliest[i]) + self.ready_lag)
            rows.append((i, int(tg.min()), int(tg.max()), step + 0.5))
        down = self.directions([(a, b) for _, a, b, _ in rows], [c for *_, c in rows], sigma0)
        out = []
        for (i, a, b, c), d in zip(rows, down):
            start, end = self.stroke_ends(a, b, d)
            n = b - a + 1
            frames = self.sweep_frames + self.sweep_extra * (n - 1)
            out.append(Sweep(i, start, end, c, _min_jerk_inverse(0.5 / n), frames, n, int(notes.onset[i + 1])))
        travels = [self._travel_frames(a.end, s.start) for a, s in zip(out[:-1], out[1:])]
        for a, s, travel in zip(out[:-1], out[1:], travels):   # a crossing after a travel short of time comes later
            late = travel + 2 * self.half_min * ((1 - a.tau) + s.tau) + self.spare - (s.cross - a.cross)
            if late > 0 and travel > 0:
                room = s.note_end - 1.5 - s.cross - (s.strings - 1)
                s.cross += float(np.clip(late, 0.0, max(0.0, min(room, self.max_delay))))
        if timing is not None:
            for prev, s in zip([None] + out[:-1], out):
                self.fit(notes, timing, s, prev)
        for a, s, travel in zip(out[:-1], out[1:], travels):   # strokes shortened to share the time between crossings
            room = s.cross - a.cross - travel
            if room < 2 * self.half_min:
                room = min(s.cross - a.cross, 2 * self.half_min)
            wa, wb = (1 - a.tau) * a.frames, s.tau * s.frames          # in proportion to what each side would take
            a.frames = min(a.frames, room * wa / (wa + wb) / (1 - a.tau))
            s.frames = min(s.frames, room * wb / (wa + wb) / s.tau)
        return out, sigma0

    def crossings(self, notes: Notes, i: int, a: int, b: int, cross: float, down: bool,
                  frames: float | None = None) -> dict:
        """{string: planned time} at which a stroke over strings a..b of `frames` (default: its full length),
        crossing its first string at `cross`, crosses each of note i's picked strings."""
        n = b - a + 1
        frames = self.sweep_frames + self.sweep_extra * (n - 1) if frames is None else frames
        t0 = cross - _min_jerk_inverse(0.5 / n) * frames
        return {int(s): t0 + _min_jerk_inverse(((b - s if down else s - a) + 0.5) / n) * frames
                for s in np.flatnonzero(notes.pick[i])}

    def short_holds(self, notes: Notes, timing: LeftTiming, i: int, a: int, b: int, cross: float, down: bool,
                    frames: float | None = None) -> int:
        """How many of note i's picked strings (a..b) a stroke (`crossings`) would pick too late for the left hand's
        press to last 2/3 of the note from the pick (the simulated pick `pick_lag` behind the plan)."""
        return self._late(notes, timing, i, self.crossings(notes, i, a, b, cross, down, frames))

    def _late(self, notes: Notes, timing: LeftTiming, i: int, times: dict) -> int:
        """`short_holds` of note i's crossing `times` ({string: planned time})."""
        need = scoring.hold_frames(int(notes.onset[i + 1] - notes.onset[i]))
        return sum(not timing.lasts(notes.left[i], s, int(np.floor(t + self.pick_lag)), need) for s, t in times.items())

    def fit(self, notes: Notes, timing: LeftTiming, sw: Sweep, prev: Sweep | None = None) -> None:
        """A stroke whose later strings would be picked too late for the left hand's press (`short_holds`): quicker,
        down to `strum_rate` steps per string, and its first crossing in the note's step 0 (at `early_cross` of the
        step, so that a tracking lag keeps it in the note) where each string crossed in that step is held as the note
        asks a step before already (the simulated left hand may lag its plan); the least change that holds the most
        strings."""
        i = sw.note
        tg = np.flatnonzero(notes.pick[i])
        a, b, down = int(tg.min()), int(tg.max()), sw.start > sw.end
        best = (self.short_holds(notes, timing, i, a, b, sw.cross, down, sw.frames), sw.cross, sw.frames)
        if best[0] == 0:
            return
        onset = int(notes.onset[i])
        floor = max(2 * self.half_min, self.strum_rate * sw.strings)
        for cross in (sw.cross, onset + self.early_cross):
            if cross < sw.cross and (onset + 0.5 >= sw.cross or onset < 1):
                continue
            if cross < sw.cross and prev is not None and cross - prev.cross < self.early_gap:
                continue
            f = sw.frames
            while f >= floor - 1e-9 and best[0] > 0:
                times = self.crossings(notes, i, a, b, cross, down, f)
                safe = all(timing.lasts(notes.left[i], s, onset - 1, 2) for s, t in times.items() if t < onset + 1)
                k = self._late(notes, timing, i, times)
                if k < best[0] and (cross == sw.cross or safe):
                    best = (k, cross, f)
                f -= 0.5
        sw.cross, sw.frames = best[1], best[2]

    def pick_path(self, notes: Notes, earliest=None) -> np.ndarray:
        """(T + 1, 3) pick point at every control step boundary (guitar frame): minimum-jerk in x from stop to stop
        (each stroke's start and end, `sweeps`), below the strings from the first stroke on, lifted at the step
        boundaries around each string passed over. earliest: as for `sweeps`."""
        sw, sigma0 = self.sweeps(notes, earliest)
        T = notes.frames
        t = np.arange(T + 1, dtype=float)
        zs = self.guitar.string_z
        out = np.zeros((T + 1, 3))
        out[:, 1] = self.y
        if not sw:
            out[:, 0], out[:, 2] = self.pick0[0], self.pick0[2]
            return out
        first = sw[0].t0
        approach = (max(0.0, first - 10.0), sigma0)              # from the home pick to the first stroke
        stops = [approach] + [p for s in sw for p in ((s.t0, s.start), (s.t1, s.end))]
        sigma = np.full(T + 1, stops[-1][1])
        sigma[t <= approach[0]] = sigma0
        for (ta, sa), (tb, sb) in zip(stops[:-1], stops[1:]):
            m = (t >= ta) & (t <= tb)
            if tb > ta:
                sigma[m] = sa + min_jerk((t[m] - ta) / (tb - ta)) * (sb - sa)
        high = np.zeros(T + 1, bool)
        legs = [(approach[0], first, sigma0, sw[0].start)] + [(a.t1, s.t0, a.end, s.start) for a, s in zip(sw, sw[1:])]
        for ta, tb, sa, sb in legs:
            for k in range(N_STRINGS):
                if min(sa, sb) < k < max(sa, sb):
                    tp = ta + _min_jerk_inverse(abs(k - sa) / abs(sb - sa)) * (tb - ta)
                    high[max(int(np.floor(tp)), 0):min(int(np.ceil(tp)), T) + 1] = True
        high |= t > sw[-1].t1 + 1
        z = np.where(high, zs + self.lift, zs - self.depth)
        before = t < first
        descent = self.pick0[2] + (zs - self.depth - self.pick0[2]) * min_jerk(t[before] / first)
        z[before] = np.maximum(z[before], descent)
        out[:, 0], out[:, 2] = self.x_of(sigma), z
        return out

    # --- inverse kinematics
    def solve(self, path: np.ndarray) -> np.ndarray:
        """(T + 1, 27) joint targets putting the pick on `path`, damped least squares warm-started frame to frame."""
        k = self.kin
        q = k.home.copy()
        out = np.empty((len(path), 27))
        act, W = self.active, np.diag(self.weights)
        for t, p in enumerate(path):
            for _ in range(4):
                k.set(q)
                e = p - k.site(k.hand.pick)
                J = k.site_jac(k.hand.pick)[:, act]
                r = -(W @ W) @ (q[act] - k.home[act])
                dq = np.linalg.solve(J.T @ J + W @ W, J.T @ e + r)
                q[act] = np.clip(q[act] + dq, k.lo[act], k.hi[act])
                if np.linalg.norm(e) < 2e-5:
                    break
            out[t] = q
        return out

    def desired(self, notes: Notes, earliest=None) -> np.ndarray:
        return self.solve(self.pick_path(notes, earliest))


def _min_jerk_inverse(frac):
    """Time fraction at which the minimum-jerk profile reaches `frac`."""
    lo, hi = 0.0, 1.0
    for _ in range(40):
        mid = (lo + hi) / 2
        lo, hi = (mid, hi) if min_jerk(mid) < frac else (lo, mid)
    return (lo + hi) / 2


# ------------------------------------------------------------------------------------------------- left hand

