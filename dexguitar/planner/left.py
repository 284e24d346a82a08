"""The fretting hand's planner: one-finger-per-fret hand positions planned over the whole song; per note, each
target string gets a fingertip on its press point resting on the fretboard while the other fingers hover 10 mm above
the strings; where that fingering does not hold the note in a short simulated trial, the cheapest other one that does
(a finger across two neighbouring strings, the index barred across all six in a hand pose of its own). Joint targets
come from least squares on the env model's kinematics, joined by minimum-jerk moves timed per finger so that each
note is held for the 2/3 the score asks (`world.scoring`). The rules in prose: docs/planner.md.
"""
from __future__ import annotations

import functools
import itertools

import jax
import jax.numpy as jnp
import numpy as np
from scipy.optimize import least_squares

from dexguitar.planner.right import LeftTiming
from dexguitar.planner.tracking import Notes, Tracker, body_jac, clearance, converge, min_jerk
from dexguitar.world import detect, scoring
from dexguitar.world import hands as H
from dexguitar.world.geometry import point_segment_distance
from dexguitar.world.guitar import GUITAR, N_STRINGS
from dexguitar.world.kinematics import HandKinematics


WRIST_THUMB = np.arange(11)                                    # wrist slides + hinges, thumb (DoF order)
FINGER_DOFS = [np.arange(11 + 4 * f, 15 + 4 * f) for f in range(4)]
HOME_POSITION = 5                                              # the home pose's index finger is over fret 5
POSTURE = np.array([0.3, -0.8, 0.8, 0.6, 0.4] + [0.6, 0.0, 1.0, 0.6] * 4)   # the rest posture (left)

# The left planner's version number, written into exported residual policies (`policy.json`'s "feedforward") so
# that older releases, which kept several planners, play them on this one; the only one `learn.policy` reads.
PLANNER_VERSION = 21
PAIR = 10               # a finger pressing strings s and s + 1 (0-based) at one fret: "string" PAIR + s
BARRE = 20              # the index across all six strings at one fret: "string" BARRE
BARRE_POSITIONS = 100   # hand position BARRE_POSITIONS + k: the barre hand at fret k (`ScriptedLeft.barre_position`)
_SOLVED: dict[tuple, tuple[dict, dict, dict]] = {}    # `ScriptedLeft`'s solves, per process (`ScriptedLeft._constants`)


def strings_of(s: int) -> tuple:
    """The strings (0-based) under a finger's "string" s: one, two for a pair (`PAIR`), all six for a barre."""
    if s == BARRE:
        return tuple(range(N_STRINGS))
    return (s - PAIR, s - PAIR + 1) if s >= PAIR else (s,)


def fret_of(p: int) -> int:
    """The index finger's fret in hand position p (a barre position's fret)."""
    return p - BARRE_POSITIONS if p > BARRE_POSITIONS else p


class ScriptedLeft:
    """The fretting hand: one finger per fret in a hand position covering 4 frets.

    A hand position p (index finger on fret p) is a whole-hand pose with the fingertips hovering over frets p..p+3
    and the thumb behind the neck; the positions are planned for the whole song, with as few and as small moves as
    cover its notes (`positions`). Per note, each target string gets the finger of its fret (`fingering` says where
    another fingering, a pair or a barre takes over), whose tip is put on p_{i,k} with the capsule resting on the
    fretboard (tip axis at fretboard top + radius, `press_depth` into it so the PD keeps it down): 3 mm from the
    string, well inside the 6 mm press distance. The other fingers hover `hover` above the strings, over the next
    place they will press.
    """

    hover = 0.010           # hovering tip axis above string height (the capsule 4 mm above the string)
    press_depth = 0.0005    # tip axis below the resting height on the fretboard
    clearance = 0.0075      # pressing finger's parts from the other strings (soft)
    lift_frames = 5
    land_frames = 5
    lead_frames = 2         # changes lead the onset by up to this, leaving 2/3 of the note before + 2
    quick_frames = 3        # a lift or landing beside a note of n < 7 frames takes max(n - 2, this)
    shift_frames = 10       # hand position change (the wrist slides are slow: kp 10 on 0.2 kg), or beside a note of
    glide_min = 5           # n < 12 frames 2 (n - 2n/3) + 2, so that each keeps 2/3 of itself, but not below this
    glide_frames = 6        # a move between two notes this short costs `glide_cost` per fret beyond one
    glide_cost = 1.5
    start_frames = 10       # from the home pose to the first note's position
    first_frames = 4        # ... or faster, down to this, to end by a first onset that comes sooner,
    first_reach = 3         # where the first position is this many frets from home or fewer (farther: the wrist lags)
    pull_lead = 0.3         # a pull-off's lift starts this fraction of its frames before the boundary
    via_shift = 2           # shifts of at most this many frets move fingers clear of open strings (`shift_via`)
    search_limit = 40       # candidate fingerings tried per note, cheapest first
    check_frames = 10       # a fingering is tried by moving to it from the note before, then holding this long
    open_clear = 0.008      # a finger lifted off a string its note wants open keeps its tip this high (`configs`)

    def __init__(self):
        self.guitar = GUITAR
        self.kin = HandKinematics("left")
        self.posture = POSTURE
        # Solved hand positions, finger poses and simulated trials. Each is a function of its key and the class's
        # constants alone, so the planners of a process share them (`_SOLVED`): the second song planned in a
        # process solves only what the first did not.
        solved = _SOLVED.setdefault(self._constants(), ({}, {}, {}))
        self._positions: dict[int, np.ndarray] = solved[0]
        self._fingers: dict[tuple, np.ndarray] = solved[1]
        self._trials: dict[tuple, np.ndarray] = solved[2]
        self._tracker = None

    def _constants(self) -> tuple:
        """What the solves read besides their keys: the class and its geometry and timing constants."""
        return (type(self), self.hover, self.press_depth, self.clearance, self.land_frames, self.shift_frames,
                self.check_frames, self.posture.tobytes())

    # --- geometry helpers
    def fret_mid(self, k: int) -> float:
        return float((self.guitar.fret_y[k] + self.guitar.fret_y[k - 1]) / 2)

    def press_point(self, s: int, k: int, f: int = 0) -> np.ndarray:
        """Tip target of finger f for string s (0-based) at fret k: on p_{s,k}, its capsule resting on the board.
        A pair (`PAIR`): midway between the two strings' points, where the finger's axis is within the press
        distance of both (3.7-4.3 mm of 6)."""
        p = np.mean([self.guitar.target_points[j, k] for j in strings_of(s)], axis=0)
        p[2] = self.guitar.fretboard_z + H.RADII[H.FINGERS[f]][2] - self.press_depth
        return p

    def hover_point(self, x: float, k: int) -> np.ndarray:
        return np.array([x, self.fret_mid(k), self.guitar.string_z + self.hover])

    def mid_x(self, k: int) -> float:
        y = self.fret_mid(k)
        return float((self.guitar.string_x(3, y) + self.guitar.string_x(4, y)) / 2)

    # --- inverse kinematics (cached)
    def position(self, p: int) -> np.ndarray:
        """27 joint values of hand position p (cached). Solved together with, for every finger, the configurations
        pressing string 1 and string 6 at its fret, so that every string is within reach from this pose; from the
        neighbouring position towards the home pose's, solved first (from the home pose itself at HOME_POSITION), so
        that the solution is the same whatever was planned before."""
        if p in self._positions:
            return self._positions[p]
        if p > BARRE_POSITIONS:
            self._positions[p] = self.barre_position(p - BARRE_POSITIONS)
            return self._positions[p]
        k, hand, g = self.kin, self.kin.hand, self.guitar
        q0 = k.home if p == HOME_POSITION else self.position(p - 1 if p > HOME_POSITION else p + 1)
        frets = [min(p + f, g.n_frets) for f in range(4)]

        def residual(z):
            q = z[:27]
            k.set(q)
            out = [10 * (k.site(hand.tips[f]) - self.hover_point(self.mid_x(frets[f]), frets[f])) for f in range(4)]
            out.append(10 * (k.site(hand.thumb_tip) - [-0.008 * g.sign, self.fret_mid(frets[1]) + 0.01, -0.02]))
            for f in range(4):                                # knuckles beside the treble edge, clear of the neck
                out.append(10 * np.array([max(0.0, 0.04 - g.sign * k.body(hand.segments[f][0])[0])]))
            out.append(0.02 * (q[6:] - self.posture))
            out.append(0.02 * (q[3:6] - k.home[3:6]))
            for j, s in enumerate((0, N_STRINGS - 1)):       # reach: press strings 1 and 6 from this wrist pose
                for f in range(4):
                    qq = q.copy()
                    qq[FINGER_DOFS[f]] = z[27 + 16 * j + 4 * f: 31 + 16 * j + 4 * f]
                    k.set(qq)
                    out.append(30 * (k.site(hand.tips[f]) - self.press_point(s, frets[f], f)))
            return np.concatenate(out)

        def jacobian(z):                                      # of `residual`, row for row
            q = z[:27]
            k.set(q)
            J = np.zeros((67, len(z)))
            for f, site in enumerate(hand.tips + (hand.thumb_tip,)):
                J[3 * f:3 * f + 3, :27] = 10 * k.site_jac(site)
            for f in range(4):
                if 0.04 - g.sign * k.body(hand.segments[f][0])[0] > 0:
                    J[15 + f, :27] = -10 * g.sign * body_jac(k, hand.segments[f][0])[0]
            J[19:40, 6:27] = 0.02 * np.eye(21)
            J[40:43, 3:6] = 0.02 * np.eye(3)
            for j in range(2):
                for f in range(4):
                    qq, cols = q.copy(), slice(27 + 16 * j + 4 * f, 31 + 16 * j + 4 * f)
                    qq[FINGER_DOFS[f]] = z[cols]
                    k.set(qq)
                    row = 43 + 12 * j + 3 * f
                    Jf = 30 * k.site_jac(hand.tips[f])
                    J[row:row + 3, cols] = Jf[:, FINGER_DOFS[f]]
                    Jf[:, FINGER_DOFS[f]] = 0.0
                    J[row:row + 3, :27] = Jf
            return J

        z0 = np.concatenate([q0, q0[11:], q0[11:]])
        lo = np.concatenate([k.lo, k.lo[11:], k.lo[11:]])
        hi = np.concatenate([k.hi, k.hi[11:], k.hi[11:]])
        self._positions[p] = converge(residual, z0, lo, hi, jacobian)[:27]
        return self._positions[p]

    def barre_position(self, fret: int) -> np.ndarray:
        """27 joint values of the barre hand at `fret`: the index's axis through every string's point in the middle
        of the fret space, at the height of a pressing fingertip's axis, the other fingertips hovering over the next
        three frets and the thumb behind the neck; wrist free, from hand position `fret`. Each string's term is its
        point's offset from its foot on the nearest index segment: the same cost as the distance, and smooth where it
        vanishes, so that the solve converges."""
        k, hand, g = self.kin, self.kin.hand, self.guitar
        y = self.fret_mid(fret)
        z = g.fretboard_z + H.RADII["index"][1] - self.press_depth
        points = np.array([[g.string_x(i + 1, y), y, z] for i in range(N_STRINGS)])
        frets = [min(fret + f, g.n_frets) for f in range(4)]

        def residual(q):
            k.set(q)
            seg = k.segments()[:3]
            d2, t = point_segment_distance(points[:, None], seg[None, :, 0], seg[None, :, 1])    # (6, 3)
            near = np.argmin(d2, axis=1)                      # each string's point to its foot on the nearest segment
            a, b = seg[near, 0], seg[near, 1]
            out = [30 * (a + t[np.arange(N_STRINGS), near][:, None] * (b - a) - points).ravel()]
            out += [10 * (k.site(hand.tips[f]) - self.hover_point(self.mid_x(frets[f]), frets[f])) for f in (1, 2, 3)]
            out.append(10 * (k.site(hand.thumb_tip) - [-0.008 * g.sign, self.fret_mid(frets[1]) + 0.01, -0.02]))
            out.append(0.01 * (q[6:] - self.posture))
            return np.concatenate(out)

        return converge(residual, self.position(fret), k.lo, k.hi)

    def finger(self, f: int, p: int, target: tuple, pressing: bool, string: int = -1) -> np.ndarray:
        """4 joint values of finger f (0 = index) in position p putting its tip on `target` (rounded to 0.1 mm).
        A pressing finger keeps its parts `clearance` away from the other strings."""
        key = (f, p, target, pressing, string)
        if key in self._fingers:
            return self._fingers[key]
        k, hand, g = self.kin, self.kin.hand, self.guitar
        base = self.position(p).copy()
        dofs = FINGER_DOFS[f]
        tip = hand.tips[f]
        others = [i for i in range(N_STRINGS) if i not in strings_of(string)]
        strings = g.strings

        def residual(x):
            q = base.copy()
            q[dofs] = x
            k.set(q)
            out = [100 * (k.site(tip) - np.asarray(target))]
            if pressing:
                seg = k.segments()[3 * f: 3 * f + 3]
                gaps = [clearance(a, b, strings[i, 0], strings[i, 1]) for a, b in seg for i in others]
                out.append(10 * np.maximum(0.0, self.clearance - np.array(gaps)))
            out.append(0.01 * (x - self.posture[5 + 4 * f: 9 + 4 * f]))
            return np.concatenate(out)

        x0 = base[dofs]
        lo, hi = k.lo[dofs], k.hi[dofs]
        x = least_squares(residual, np.clip(x0, lo + 1e-6, hi - 1e-6), bounds=(lo, hi)).x
        x = converge(residual, x, lo, hi)        # to the minimum of the basin that solve found (a stretch has several)
        self._fingers[key] = x
        return x

    # --- the schedule
    def fingering(self, notes: Notes):
        """Per note: (hand position, {finger: (string, fret)}). Hand positions are planned for the whole song
        (`positions`); in them, one finger per fret (`rule`): chords by fret (index on the lowest), at one fret the
        string nearer string 6 first, more than 4 pressed strings keep the 4 lowest frets. A note that the fingering
        of the note before plays keeps it (`kept`); neighbouring strings at one fret take one finger where that holds
        (`pair_fingering`); fingers do not jump between hurried notes (`search_steady`); where the rule's fingering
        does not hold the note, the cheapest that does (`search_fingering`), else a barre (`barre_fingering`), else
        the one that holds the most of it (`search_partial`); a guide finger keeps its place (`guided`), a trill its
        lower finger (`anchored`); a barre stays over the notes around it that it plays (`extend_barres`)."""
        return self.plans(notes)[0]

    def plans(self, notes: Notes):
        """(`fingering`, the same without barres): an idle finger hovers over where it presses next in its hand
        position as if no note were barred (`configs`). With barres taken into account the idle fingers of
        `sonata`'s notes 41-51 would hover elsewhere, one of them settling on the strings: 10 notes lost."""
        p, out, ahead = None, [], []
        planned = self.positions(notes)
        for i in range(notes.n):
            goal = notes.left[i]
            press = sorted(((int(goal[s]), -s) for s in range(N_STRINGS) if goal[s] > 0))[:4]
            if not press:
                out.append((p, {}))
                ahead.append((p, {}))
                continue
            before = next(((q, f) for q, f in reversed(out) if q is not None), None)
            kept = self.kept(goal, before)
            if kept is not None:
                p = kept[0]
                out.append(kept)
                ahead.append(kept)
                continue
            paired = self.pair_fingering(goal, planned[i], before)
            if paired is not None:
                p = paired[0]
                out.append(paired)
                ahead.append(paired)
                continue
            p, fingers = self.rule(press, planned[i])
            if len(press) == 1 and self.hurried(notes, i) and self.jumps(before, p, fingers):
                p, fingers = self.search_steady(p, fingers, press, goal, before)
            if not self.holds(p, fingers, goal, before):
                p, fingers = self.search_fingering(p, fingers, press, goal, before)
                barre = None
                if not self.holds(p, fingers, goal, before):
                    barre = self.barre_fingering(goal, before)
                if not self.holds(p, fingers, goal, before):        # also for `ahead` under a barre
                    p, fingers = self.search_partial(p, fingers, goal, before)
                if barre is not None:
                    out.append(barre)
                    ahead.append((p, fingers))
                    continue
            fingers = self.guided(p, fingers, press, goal, before)
            nxt = notes.left[i + 1] if i + 1 < notes.n else None
            fingers = self.anchored(p, fingers, goal, out[-1] if out else None, nxt)
            out.append((p, fingers))
            ahead.append((p, fingers))
        self.extend_barres(notes, out)
        return _filled(out), _filled(ahead)

    def kept(self, goal, before: tuple | None):
        """The fingering of the note before (`before`: position, fingers) where it plays this note too
        (`covers`, `holds`); else None. A partial strum of a chord then keeps the whole chord down, as a guitarist
        does, where the fingering searched for the note alone would regrip (`snow`'s "7 9 9 x x x" after its
        "7 9 9 8 7 7": every finger lifted and landed again, both notes lost). Keeping only the fingers that press
        the note, the others lifted to hover ahead, plays 3 of the 15 official songs worse than keeping them all and
        none better."""
        if before is None or before[0] >= BARRE_POSITIONS or not before[1] or not covers(before[1], goal):
            return None
        return before if self.holds(*before, goal, before) else None

    def guided(self, p: int, fingers: dict, press: list, goal, before: tuple | None) -> dict:
        """Where a place pressed in the note before, in the same hand position, is pressed again by
        another finger, the cheapest fingering that leaves it under the same finger (`fingerings`) if one holds the
        note; else `fingers`. A guitarist keeps such a guide finger down. Moved from the middle finger to the index,
        `sonata`'s bass, string 6 at fret 1 under `1 x x 0 1 0` then `1 3 x x x x`, would take the index across the
        open string 3 and off string 2 before its note had held 2/3 of itself."""
        if before is None or before[0] != p:
            return fingers
        stay = {sk: f for f, sk in before[1].items() if sk in fingers.values()}
        if all(fingers.get(f) == sk for sk, f in stay.items()):
            return fingers
        cands = [c for c in self.fingerings(press, p) if c[1] == p and all(c[2].get(f) == sk for sk, f in stay.items())]
        found = self.first_holding(cands, goal, before)
        return found[1] if found is not None else fingers

    def anchored(self, p: int, fingers: dict, goal, prev: tuple | None, nxt) -> dict:
        """A trill: a single note above the note before on the same string, in the same hand position,
        and the next note back at that lower fret alone, keeps the lower finger down under it (the highest fret
        sounds), as a guitarist does. Going back down is then a pull-off: the lower fret sounds the moment the upper
        finger lifts, so the lift waits for the boundary (`desired`) instead of leaving early for a landing that lags.
        Lifting the lower finger and pressing it again, `flight_of_the_bumblebee1`'s trills (string 3, frets 6-7-6 in
        5-frame notes) hold each upper note 3 of the 4 frames it needs. Anchoring wherever a line goes up a string
        keeps fingers from getting ready for the notes after it (`beethoven_virus` loses a note)."""
        if prev is None or prev[0] != p or len(fingers) != 1 or nxt is None:
            return fingers
        (f, (s, k)), = fingers.items()
        low = [(g, sk) for g, sk in prev[1].items() if sk[0] == s < PAIR and sk[1] < k and g < f]
        if len(low) != 1 or sorted(np.flatnonzero(np.asarray(nxt) > 0)) != [s] or nxt[s] != low[0][1][1]:
            return fingers
        trial = {**fingers, low[0][0]: low[0][1]}
        return trial if self.holds(p, trial, goal, prev) else fingers

    def rule(self, press: list, p: int):
        """The one-finger-per-fret rule for the pressed (fret, -string) of `press` (fret order, at most 4) in hand
        position p (`positions`): (p, {finger: (string, fret)})."""
        return p, _by_fret(press, p)

    def positions(self, notes: Notes) -> list:
        """The hand position of each note (None: nothing pressed) for the whole song at once, by dynamic
        programming: each note's position covers its pressed frets (a span of more than 4 frets: its lowest), and the
        song has as few moves as can be (each costs 1 + 0.05 per fret), from the home pose's position; of plans as
        good, the one that moves latest. Moving only when a note leaves the position, by the least amount, an
        ascending line would move at every note where one move covers it. Between two notes of at most
        `glide_frames` each fret of a move beyond the first costs `glide_cost` more, since the wrist cannot cross
        four frets in the slack of a 5-frame note but follows one fret a note, the finger sliding along its string."""
        top = self.guitar.n_frets - 3
        allowed = []
        for goal in notes.left:
            frets = [int(v) for v in goal if v > 0]
            if not frets:
                allowed.append(None)
                continue
            lo, hi = min(frets), max(frets)
            allowed.append(list(range(max(1, hi - 3), min(lo, top) + 1)) if hi - lo <= 3 else [min(lo, top)])

        short = (np.diff(notes.onset) <= self.glide_frames) & np.array([a is not None for a in allowed], bool)
        fast = np.zeros(notes.n, bool)      # note i and the note before, both pressed, both short
        fast[1:] = short[1:] & short[:-1]

        def move(q, p, i):          # a later move costs a little less: of equal plans, the one that moves late
            d = abs(q - p)
            extra = self.glide_cost * max(d - 1, 0) if fast[i] else 0.0
            return (q != p) * (1 + 0.05 * d + extra - 1e-4 * i)

        cost, back = {HOME_POSITION: 0.0}, []
        for i, ps in enumerate(allowed):
            if ps is None:
                back.append(None)
                continue
            step = {p: min(cost, key=lambda q: (cost[q] + move(q, p, i), abs(q - p))) for p in ps}
            cost = {p: cost[q] + move(q, p, i) for p, q in step.items()}
            back.append(step)
        out, p = [None] * notes.n, min(cost, key=cost.get)
        for i in reversed(range(notes.n)):
            if back[i] is not None:
                out[i], p = p, back[i][p]
        return out

    def pair_fingering(self, goal, p: int, before: tuple | None):
        """Where two neighbouring strings are pressed at one fret, the rule's fingering in hand position p with one
        finger across each such pair (`PAIR`; pairs taken from string 6 up), if it holds the whole note (`holds`);
        else the cheapest fingering with those pairs that does (the rule's order of fingers at one fret can cross
        them), or None. It frees a finger for the rest of a chord (five or six pressed strings with four fingers) and
        lets a double stop move as one finger."""
        units = _paired(sorted((int(goal[s]), -s) for s in range(N_STRINGS) if goal[s] > 0))
        if len(units) == int(np.sum(goal > 0)) or len(units) > 4:
            return None
        q, fingers = self.rule(sorted(units), p)
        if self.holds(q, fingers, goal, before):
            return q, fingers
        return self.first_holding(self.fingerings(sorted(units), q), goal, before)

    def pose(self, p: int, fingers: dict) -> np.ndarray:
        """27 joint values of position p with `fingers` ({finger: (string, fret)}) pressing, the others hovering over
        their own frets."""
        g = self.guitar
        q = self.position(p).copy()
        for f in range(4):
            if f in fingers:
                s, k = fingers[f]
                q[FINGER_DOFS[f]] = self.pressing(f, p, s, k)
            else:
                k = min(fret_of(p) + f, g.n_frets)
                q[FINGER_DOFS[f]] = self.finger(f, p, _key(self.hover_point(self.mid_x(k), k)), False)
        return q

    def pressing(self, f: int, p: int, s: int, k: int) -> np.ndarray:
        """4 joint values of finger f in position p pressing string s (0-based) at fret k (a barre: the barre
        position's own index)."""
        if s == BARRE:
            return self.position(p)[FINGER_DOFS[f]]
        return self.finger(f, p, _key(self.press_point(s, k, f)), True, s)

    def holds(self, p: int, fingers: dict, goal, before=None) -> bool:
        """Does this fingering press exactly what `goal` asks (the env's press detection), both as a static pose
        and in simulation, reached from the pose of the note before (`before`: (position, fingers); None: this
        position's hover pose) and held? Fingers collide with each other and with the strings, which the pose
        alone does not show."""
        self.kin.set(self.pose(p, fingers))
        return bool(np.all(scoring.left_ok(_pressed(self.kin.segments()), goal))
                    and np.all(scoring.left_ok(self.trial(p, fingers, before), goal)))

    def held(self, p: int, fingers: dict, goal, before=None) -> int:
        """How many of the strings that `goal` concerns (pressed at a fret or open) end in their state in `trial`."""
        ok = np.asarray(scoring.left_ok(self.trial(p, fingers, before), goal))
        return int(np.sum(ok & (np.asarray(goal) != 0)))

    def trial(self, p: int, fingers: dict, before=None) -> np.ndarray:
        """(6,) frets pressed (the env's detection) after this fingering is reached in simulation (MuJoCo C) from
        the pose of the note before (`before`: (position, fingers); None: this position's hover pose) and held for
        `check_frames`."""
        before = before or (p, {})
        key = (p, tuple(sorted(fingers.items())), before[0], tuple(sorted(before[1].items())))
        if key not in self._trials:
            if self._tracker is None:
                self._tracker = Tracker("left")
            q, q0 = self.pose(p, fingers), self.pose(*before)
            move = self.land_frames if before[0] == p else self.shift_frames
            s = min_jerk(np.arange(move + self.check_frames + 1) / move)[:, None]
            _, qs = self._tracker.track(q0 + s * (q - q0), start=True)
            self.kin.set(qs[-1])
            self._trials[key] = _pressed(self.kin.segments())
        return self._trials[key]

    def barre_fingering(self, goal, before: tuple | None, low: int | None = None):
        """The index barred across all six strings at fret `low` (default: the note's lowest, pressed on two
        strings or more; `barre_position`), the higher frets by the rule with the other three fingers, if that holds
        the note (`holds`); else the cheapest other fingers above the barre that do (`barre_others`), or None. Never
        where a string must ring open (the barre would stop it)."""
        goal = np.asarray(goal)
        if np.any(goal == -1) or (low is None and not np.any(goal > 0)):
            return None
        if low is None:
            low = int(goal[goal > 0].min())
            if np.sum(goal == low) < 2:
                return None
        rest = sorted((int(goal[s]), -s) for s in range(N_STRINGS) if goal[s] > low)
        if np.any((goal > 0) & (goal < low)) or len(rest) > 3 or (rest and rest[-1][0] > low + 3):
            return None
        fingers = {0: (BARRE, low)} | _by_fret(rest, low, first=1)
        p = BARRE_POSITIONS + low
        if self.holds(p, fingers, goal, before):
            return p, fingers
        return self.first_holding(self.barre_others(rest, low), goal, before)

    def barre_others(self, rest: list, low: int) -> list:
        """[(cost, barre position, fingers)] for the frets above a barre at `low` (`rest`: (fret,
        -string), fret order), where the rule's fingers do not hold: any of the other three fingers, in fret order,
        two neighbouring strings at one fret also as one finger across them (`PAIR`). `sonata`'s `1 x x 3 3 1` under
        the barre of the notes beside it: ring and pinky on strings 3 and 2 at fret 3 press fret 1 on string 2
        (a pinky this short lies flat); the ring finger across both holds, where leaving the barre for a fingering of
        its own and back holds the note 6 of its 18 frames."""
        paired, out = _paired(rest), []
        for units in ([paired] if paired != rest else []) + [rest]:
            for chosen in itertools.combinations((1, 2, 3), len(units)):
                stretch = sum(abs(k - low - f) for f, (k, _) in zip(chosen, units))
                out.append((stretch + (units is rest), BARRE_POSITIONS + low,
                            {0: (BARRE, low)} | {f: (-ms, k) for f, (k, ms) in zip(chosen, units)}))
        return out

    def extend_barres(self, notes: Notes, out: list) -> None:
        """A barre stays for the notes around it that it can play (no open string, every pressed fret within the
        barre's four; `barre_fingering` at its fret holds them), as a guitarist keeps a barre down over a passage
        instead of moving the whole hand out of it and back for a note or two (in `out`, in place). An extension
        ends before a note it would leave with a hand position change at each end (`squeezes`)."""
        barres = [i for i, (p, _) in enumerate(out) if p is not None and p > BARRE_POSITIONS]
        for i in barres:
            low = fret_of(out[i][0])
            for step in (1, -1):
                j, was = i + step, {}
                while 0 <= j < notes.n and not (out[j][0] is not None and out[j][0] == out[i][0]):
                    before = next(((q, f) for q, f in reversed(out[:j]) if q is not None), None)
                    barre = self.barre_fingering(notes.left[j], before, low) if np.any(notes.left[j] > 0) else None
                    if barre is None:
                        break
                    was[j], out[j] = out[j], barre
                    j += step
                while was and self.squeezes(out, i, j, step, was):
                    j -= step
                    out[j] = was.pop(j)

    @staticmethod
    def squeezes(out: list, i: int, j: int, step: int, was: dict) -> bool:
        """Does extending the barre of note i over the notes `was` (index: their own plan) save no hand
        position change, and move one onto note j, the first it does not cover, which has one at its other end?
        Kept through `sonata`'s `x 2 x x 3 3`, the barre would leave the next note, `x 3 x x 3 3` in position 1,
        between a change from the barre and one to position 3: it would hold 10 of its 18 frames."""
        n = len(out)
        if not (0 <= j < n and 0 <= j + step < n) or out[j + step][0] == out[j][0]:
            return False
        old = [out[i][0]] + [q for q, _ in was.values()] + [out[j][0]]
        return sum(a != b for a, b in zip(old, old[1:])) == 1

    def search_partial(self, p0: int, fingers0: dict, goal, before: tuple | None):
        """Where no fingering holds the whole note (`search_fingering` found none): of the cheapest `search_limit`
        fingerings of any min(4, n) of its n pressed strings (`fingerings`), the one that holds the most strings of
        the note (`held`), the rule's own (p0, fingers0) among them. A six-string barre played as four of its strings
        scores F1 0.8 (precision 1, recall 4/6), where a fingering that slips scores nothing. Where no hand position
        spans those strings (a note over seven frets), fingerings of one string fewer, and so on."""
        pressed = [(int(goal[s]), -s) for s in range(N_STRINGS) if goal[s] > 0]
        cands = []
        for k in range(min(4, len(pressed)), 0, -1):      # fewer strings where no position spans them
            cands = [c for subset in itertools.combinations(pressed, k) for c in self.fingerings(sorted(subset), p0)]
            if cands:
                break
        cands.sort(key=lambda c: c[0])
        best, best_n = (p0, fingers0), self.held(p0, fingers0, goal, before)
        for _, p, fingers in cands[:self.search_limit]:
            n = self.held(p, fingers, goal, before)
            if n > best_n:
                best, best_n = (p, fingers), n
        return best

    def fingerings(self, press: list, p0: int) -> list:
        """[(cost, p, {finger: (string, fret)})] for the pressed (fret, -string) of `press` (fret order): hand
        positions p whose 4 frets cover them, any fingers in fret order, notes at one fret in either string order.
        Cost: stretch (frets between a finger and its own fret) plus twice the change from position p0."""
        lo, hi, m = press[0][0], press[-1][0], len(press)
        orders = [press]
        if len({k for k, _ in press}) < m:
            orders.append(sorted(press, key=lambda x: (x[0], -x[1])))
        out = []
        for p in range(max(1, hi - 3), min(lo, self.guitar.n_frets - 3) + 1):
            for chosen in itertools.combinations(range(4), m):
                for order in orders:
                    stretch = sum(abs(k - p - f) for f, (k, _) in zip(chosen, order))
                    out.append((stretch + 2 * abs(p - p0), p, {f: (-ms, k) for f, (k, ms) in zip(chosen, order)}))
        return out

    def hurried(self, notes: Notes, i: int) -> bool:
        """Is the change into note i too quick for a finger to move between strings? A move takes `lift_frames` + 1
        frames; it fits where the note before and note i can spare the third of each that need not be held. Notes
        shorter than 7 frames have quicker moves (`quick_frames`)."""
        if i == 0:
            return False
        n_a, n_b = (notes.onset[j + 1] - notes.onset[j] for j in (i - 1, i))
        return n_b >= 7 and (n_a + n_b) / 3 < self.lift_frames + 1

    @staticmethod
    def jumps(before: tuple | None, p: int, fingers: dict) -> bool:
        """Does a finger press this note somewhere other than where it pressed the note before, in the same hand
        position? It must then lift, cross and land between the two notes (`desired`: a move of `lift_frames` + 1),
        which leaves an 8-frame note less than the 2/3 it must be held."""
        return (before is not None and before[0] == p
                and any(f in before[1] and before[1][f][0] != s for f, (s, _) in fingers.items()))

    def search_steady(self, p0: int, fingers0: dict, press: list, goal, before: tuple):
        """Where the rule's fingering makes a finger jump (`jumps`), the cheapest fingering in the same
        position without a jump that holds the note (`holds`); none holds: the rule's own."""
        steady = [c for c in self.fingerings(press, p0) if c[1] == p0 and not self.jumps(before, p0, c[2])]
        return self.first_holding(steady, goal, before) or (p0, fingers0)

    def search_fingering(self, p0: int, fingers0: dict, press: list, goal, before: tuple | None):
        """The cheapest fingering (`fingerings`) that holds the note (`holds`), where the one-finger-per-fret rule's
        does not. Each is tried coming from the note before (`before`: its position and fingers), so that a swap of
        fingers on a held string shows. None holds: the rule's own (p0, fingers0)."""
        return self.first_holding(self.fingerings(press, p0), goal, before) or (p0, fingers0)

    def first_holding(self, cands: list, goal, before: tuple | None):
        """(p, fingers) of the cheapest of `cands` ((cost, p, fingers); the `search_limit` cheapest tried, in a
        stable order) that holds the note (`holds`), or None."""
        for _, p, fingers in sorted(cands, key=lambda c: c[0])[:self.search_limit]:
            if self.holds(p, fingers, goal, before):
                return p, fingers
        return None

    def configs(self, notes: Notes, plan, ahead=None):
        """Per note: the 27 joint values (wrist and thumb of its position, each finger pressing or hovering over the
        next place it presses in `ahead`, default `plan`) and, per finger, a via configuration for a same-finger move
        (or None). A finger that lets go of a place for a note that wants its string open, and presses it again
        after, hovers over its own fret instead where over that place it cannot lift its tip `open_clear` above the
        strings (a stretch beyond its own fret): there it stayed within the press distance and sounded the string."""
        ahead = plan if ahead is None else ahead
        g = self.guitar
        out = []
        for i, (p, fingers) in enumerate(plan):
            q = self.position(p).copy()
            vias = [None] * 4
            for f in range(4):
                if f in fingers:
                    s, k = fingers[f]
                    q[FINGER_DOFS[f]] = self.pressing(f, p, s, k)
                    if (i > 0 and f in plan[i - 1][1] and plan[i - 1][1][f] != (s, k) and plan[i - 1][0] == p
                            and BARRE not in (s, plan[i - 1][1][f][0])):
                        via = self.hover_point(float(self.press_point(s, k, f)[0]), k)
                        via[2] = g.string_z + 0.007
                        vias[f] = self.finger(f, p, _key(via), False)
                    continue
                nxt = next(((ahead[j][1][f]) for j in range(i + 1, len(plan))
                            if ahead[j][0] == p and f in ahead[j][1]), None)
                hk = min(fret_of(p) + f, g.n_frets)
                home = self.hover_point(self.mid_x(hk), hk)
                target = home if nxt is None else self.hover_point(float(self.press_point(*nxt, f)[0]), nxt[1])
                q[FINGER_DOFS[f]] = self.finger(f, p, _key(target), False)
                if (nxt is not None and nxt[0] < BARRE and i > 0 and plan[i - 1][0] == p
                        and plan[i - 1][1].get(f) == nxt and any(notes.left[i][j] < 0 for j in strings_of(nxt[0]))
                        and self.tip_height(q, f) < self.open_clear):
                    q[FINGER_DOFS[f]] = self.finger(f, p, _key(home), False)
            out.append((q, vias))
        return out

    def tip_height(self, q: np.ndarray, f: int) -> float:
        """Finger f's tip axis above the strings' plane in pose q."""
        self.kin.set(q)
        return float(self.kin.site(self.kin.hand.tips[f])[2] - self.guitar.string_z)

    def desired(self, notes: Notes) -> np.ndarray:
        """(T + 1, 27) joint targets. Row j is the pose after control step j - 1; note i owns rows onset_i + 1 ..
        onset_{i+1}. Each change is timed against the note boundary tb = onset_i + 0.5, up to `lead_frames` earlier
        where the note before can spare it: a press that cannot spoil the previous note lands early, one that can
        lands right after tb (a double stop hammered on a frame sooner, where the note before can spare it); a lift
        that cannot spoil the next note waits, one that can is released before tb, a pull-off's at tb; lifts and
        landings beside notes shorter than 7 frames are quicker (`quick_frames`). A hand position change takes its
        frames from the notes on either side of tb in proportion to what each can spare, and fewer between short
        notes (`glide_min`); the first move, from the home pose, ends by an early first onset (`first_frames`)."""
        plan, ahead = self.plans(notes)
        cfg = self.configs(notes, plan, ahead)
        T = notes.frames
        groups = [WRIST_THUMB] + FINGER_DOFS
        events = [[] for _ in groups]                    # per group: (t0, t1, q_to, via)
        slides = []                                      # (t0, t1, finger, string, fret from, fret to)
        for i in range(notes.n):
            q, vias = cfg[i]
            tb = notes.onset[i] + 0.5
            if i == 0:
                start = self.start_frames
                if abs(fret_of(plan[0][0]) - HOME_POSITION) <= self.first_reach:
                    first = next((j for j in range(notes.n) if np.any(notes.left[j] != 0)), 0)
                    start = min(start, max(self.first_frames, int(notes.onset[first])))   # a song that starts at once
                for gi, dofs in enumerate(groups):
                    events[gi].append((0.0, float(start), q[dofs], None))
                continue
            dur = notes.onset[i] - notes.onset[i - 1]           # the note before
            tb -= min(self.lead_frames, max(0, _spare(dur) - 2))     # before the onset, into the note before's slack
            q_prev = cfg[i - 1][0]
            (p_a, f_a), (p_b, f_b) = plan[i - 1], plan[i]
            goal_a, goal_b = notes.left[i - 1], notes.left[i]
            short = min(notes.onset[i + 1] - notes.onset[i], dur)
            if p_a != p_b:
                # between short notes quicker, so that each keeps 2/3 of itself
                w = min(self.shift_frames, max(self.glide_min, 2 * _spare(short) + 2))
                sa, sb = _spare(dur), _spare(notes.onset[i + 1] - notes.onset[i])
                # from each note in proportion to the frames it can spare
                t0 = tb - w * sa / (sa + sb) if sa + sb > 0 else tb - w / 2
                for gi, dofs in enumerate(groups):
                    via = self.shift_via(gi - 1, plan[i - 1], plan[i], goal_a, goal_b) if gi > 0 else None
                    late = via is not None and gi - 1 in f_a and gi - 1 not in f_b     # a lift: press to the end
                    events[gi].append((t0 + w / 2 if late else t0, t0 + w, q[dofs], via))
                for f in set(f_a) & set(f_b):                  # same finger, same string: slide along it
                    if f_a[f][0] == f_b[f][0] != BARRE:
                        slides.append((t0, t0 + w, f, f_b[f][0], f_a[f][1], f_b[f][1]))
                continue
            lift, land = (min(x, max(self.quick_frames, short - 2)) for x in (self.lift_frames, self.land_frames))
            for f in range(4):
                dofs = FINGER_DOFS[f]
                if np.allclose(q[dofs], q_prev[dofs]):
                    continue
                a, b = f_a.get(f), f_b.get(f)
                if a is not None and b is not None:                     # move: lift, travel, press
                    D = lift + 1
                    t0 = tb - D / 2
                elif a is not None:                                     # lift
                    s, k = a
                    D = lift
                    t0 = tb + 0.5 if _harmless(goal_b, s, k) else tb - 0.5 - 0.4 * D
                    if _pull_off(f_a, f_b, s, goal_b):                  # the fret below sounds at once
                        t0 = tb - 0.5 - self.pull_lead * D
                elif b is not None:                                     # land
                    s, k = b
                    D = land
                    t0 = tb - 1.5 - D if _harmless(goal_a, s, k) else tb + 1.0 - 0.6 * D
                    if PAIR <= s < BARRE and all(0 < goal_a[j] < k for j in strings_of(s)):
                        t0 -= min(1, _spare(dur))       # a double stop hammered on: pressed a frame sooner
                else:                                                   # hover somewhere else
                    D = land
                    t0 = tb - D
                events[f + 1].append((t0, t0 + D, q[dofs], vias[f]))
        out = np.empty((T + 1, 27))
        home = self.kin.home
        t = np.arange(T + 1, dtype=float)
        for gi, dofs in enumerate(groups):
            cur = home[dofs].copy()
            val = np.tile(cur, (T + 1, 1))
            free = 0.0
            for t0, t1, q_to, via in events[gi]:
                if t0 < free:                                 # never start before the last change ended
                    t1, t0 = t1 + free - t0, free
                m = t >= t0
                if via is None:
                    s = min_jerk((t[m] - t0) / (t1 - t0))[:, None]
                    val[m] = cur + s * (q_to - cur)
                else:
                    tm = (t0 + t1) / 2
                    s1 = min_jerk((t[m] - t0) / (tm - t0))[:, None]
                    s2 = min_jerk((t[m] - tm) / (t1 - tm))[:, None]
                    val[m] = cur + s1 * (via - cur) + s2 * (q_to - via)
                cur, free = q_to, t1
            out[:, dofs] = val
        for t0, t1, f, s, ka, kb in slides:             # the tip stays on the string while the wrist moves
            pa, pb = self.press_point(s, ka, f), self.press_point(s, kb, f)
            x = out[max(int(np.floor(t0)), 0), FINGER_DOFS[f]].copy()
            for j in range(max(int(np.ceil(t0)), 0), min(int(np.floor(t1)), T) + 1):
                u = min_jerk((j - t0) / (t1 - t0))
                x = self.track_tip(f, out[j], pa + u * (pb - pa), x)
                out[j, FINGER_DOFS[f]] = x
        return out

    def shift_via(self, f: int, a: tuple, b: tuple, goal_a, goal_b):
        """Finger f's via configuration for a hand position change from a to b (position, fingers), or
        None. A finger that leaves its string, or lands on a new one, passes 7 mm above the place it presses (the
        new one, else the old one), as within a position (`configs`). Joined straight in joint space while the wrist
        moves, such fingers cross the next string: in `spring_overture`'s `10 0 0` -> `8 0 0` (position 9 to 8) the
        middle finger leaving fret 10 and the index landing on fret 8 would press string 2, which both notes want
        open, for 3 frames after the change. Only where a string beside the finger is open in either note: elsewhere
        the straight path plays five official songs better; and only in shifts of up to `via_shift` frets: in jumps
        the detour takes the 48 held-out songs from 0.8114 to 0.8011. A finger that only leaves keeps pressing through
        the first half of the shift (`desired`); lifted at once, spring's long notes would lose a frame of their
        hold."""
        (p_a, f_a), (p_b, f_b) = a, b
        old, new = f_a.get(f), f_b.get(f)
        if (max(p_a, p_b) >= BARRE_POSITIONS or old == new or (old and new and old[0] == new[0])
                or abs(p_a - p_b) > self.via_shift):
            return None                         # barres, a finger that stays, a slide along one string, a jump
        p, (s, k) = (p_b, new) if new is not None else (p_a, old)
        if s >= BARRE:
            return None
        near = [j for j in range(min(strings_of(s)) - 1, max(strings_of(s)) + 2) if 0 <= j < N_STRINGS]
        if not any(goal_a[j] < 0 or goal_b[j] < 0 for j in near if j not in strings_of(s)):
            return None                                 # no open string beside it that a brush would spoil
        via = self.hover_point(float(self.press_point(s, k, f)[0]), k)
        via[2] = self.guitar.string_z + 0.007
        return self.finger(f, p, _key(via), False)

    def track_tip(self, f: int, q: np.ndarray, target: np.ndarray, x: np.ndarray, iters: int = 6) -> np.ndarray:
        """Finger f's 4 joints putting its tip on `target` with the rest of the hand at q (Gauss-Newton)."""
        k, dofs, tip = self.kin, FINGER_DOFS[f], self.kin.hand.tips[f]
        q = q.copy()
        for _ in range(iters):
            q[dofs] = x
            k.set(q)
            e = target - k.site(tip)
            if np.linalg.norm(e) < 1e-5:
                break
            J = k.site_jac(tip)[:, dofs]
            x = np.clip(x + np.linalg.solve(J.T @ J + 1e-6 * np.eye(4), J.T @ e), k.lo[dofs], k.hi[dofs])
        return x

    def ready_steps(self, notes: Notes, q: np.ndarray) -> np.ndarray:
        """(n,) per note, the first control step whose simulated left hand (joint values q (T + 1, 27) of a tracked
        plan) holds every string as the note asks, by the env's press detection; the note's onset where it never
        does. The right hand's planner crosses a note's strings after it (`ScriptedRight.sweeps`, `earliest`)."""
        return self.timing(notes, q).ready

    def timing(self, notes: Notes, q: np.ndarray) -> LeftTiming:
        """`ready_steps` and the frets pressed after every step, for the right hand's planner in the duet."""
        segs = []
        for j in range(1, len(q)):                        # state after step j - 1
            self.kin.set(q[j])
            segs.append(self.kin.segments())
        press = np.asarray(jax.vmap(lambda s: detect.pressed_frets(s, self.guitar))(
            jnp.asarray(np.array(segs), jnp.float32)))
        out = notes.onset[:-1].copy()
        for i in range(notes.n):
            a, b = notes.onset[i], notes.onset[i + 1]
            ok = np.asarray(scoring.left_ok(jnp.asarray(press[a:b]), jnp.asarray(notes.left[i]))).all(axis=1)
            out[i] = a + int(np.argmax(ok)) if ok.any() else a
        return LeftTiming(out, press)


@functools.cache
def _press_fn():
    return jax.jit(lambda segs: detect.pressed_frets(segs, GUITAR))


def _pressed(segments) -> np.ndarray:
    """(6,) frets pressed by finger segments (12, 2, 3), as the env detects them."""
    return np.asarray(_press_fn()(jnp.asarray(segments, jnp.float32)))


def _spare(n: int) -> int:
    """Frames of an n-frame note beyond the 2/3 of it that must be held (`scoring.close`)."""
    return n - scoring.hold_frames(n)


def _by_fret(press: list, p: int, first: int = 0) -> dict:
    """{finger: (string, fret)} for the pressed (fret, -string) of `press` (fret order) in position p: each on the
    finger of its fret where it can be, fingers `first`..3 in fret order, leaving one finger for each later note."""
    fingers, f_prev = {}, first - 1
    for j, (k, ms) in enumerate(press):
        f = max(f_prev + 1, min(k - p, 3 - (len(press) - 1 - j)))
        fingers[f] = (-ms, k)
        f_prev = f
    return fingers


def _paired(press: list) -> list:
    """The pressed (fret, -string) of `press` (fret order) with each two neighbouring strings at one fret as one unit,
    (fret, -(PAIR + s)) for strings s and s + 1, taken from string 6 up."""
    out, j = [], 0
    while j < len(press):
        (k, ms), nxt = press[j], press[j + 1] if j + 1 < len(press) else None
        if nxt is not None and nxt[0] == k and nxt[1] == ms + 1:
            out.append((k, -(PAIR - nxt[1])))
            j += 2
        else:
            out.append((k, ms))
            j += 1
    return out


def _filled(plan: list) -> list:
    """A plan with the hand position of each note that presses nothing (None) taken from the note before (the first
    notes': from the first that presses)."""
    last = next((q for q, _ in plan if q is not None), 1)
    out = []
    for q, fingers in plan:
        last = q if q is not None else last
        out.append((last, fingers))
    return out


def covers(fingers: dict, goal) -> bool:
    """Does this fingering play the left goal as the env detects it: each string pressed at its fret k > 0 (by a
    finger there and none higher up), no open string (-1) pressed; free strings (0) may be pressed."""
    top = np.zeros(N_STRINGS, int)
    for s, k in fingers.values():
        for j in strings_of(s):
            top[j] = max(top[j], k)
    return bool(np.all(scoring.left_ok(top, np.asarray(goal))))


def _pull_off(f_a: dict, f_b: dict, s: int, goal_b) -> bool:
    """Does a finger lifting from string s uncover one that stays down on it at the next note's fret?"""
    return s < PAIR and goal_b[s] > 0 and any(f_a.get(g) == v == (s, int(goal_b[s])) for g, v in f_b.items())


def _harmless(goal, s: int, k: int) -> bool:
    """Would a finger at fret k on string s (and, on its way, over string s - 1: fingers come from the string-1 side)
    leave a note with this left goal unchanged? Yes where the string is free (goal 0) or pressed at a fret >= k
    (the highest fret wins); never on an open string. A pair (`PAIR`): both its strings."""
    on = strings_of(s)
    return all(goal[j] == 0 or k <= goal[j] for j in (on[0] - 1,) + on if 0 <= j < N_STRINGS)


def _key(p) -> tuple:
    """A cache key for a target point: rounded to 0.1 mm."""
    return tuple(float(x) for x in np.round(np.asarray(p, float), 4))
