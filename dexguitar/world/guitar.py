"""Guitar geometry: the one place that knows where strings, frets and target points are.

Everything that needs a string or fret position (MJCF assembly, press/pick detection, rewards, rendering, audio)
reads it from here. Numbers follow the authors' model (reference §1): 22 frets, scale length 0.621365 m.

Guitar frame (metres): x across the neck (+x toward string 1, high E), y along the neck (+y toward the headstock),
z the fretboard normal (toward the audience). Strings are numbered 1 (high E) ... 6 (low E). A mirrored guitar
(left-handed player) negates every x.
"""
from __future__ import annotations

import dataclasses
import functools

import numpy as np

N_STRINGS = 6
N_FRETS = 22
SCALE_LENGTH = 0.621365          # nut to bridge, m (reference §1.2; the paper's "24.5 inch")
NUT_Y = 0.2165                   # guitar-frame y of the nut
FRETBOARD_Z = 0.0093             # top of the fretboard
STRING_Z = 0.0123                # string height, 3 mm above the fretboard, constant along the string
NECK_END_Y = -0.2418             # end of the fretboard toward the body
NECK_HALF_WIDTH = (0.0204, 0.0279)  # at the nut and at the end of the fretboard
STRING_X_NUT = (0.01765, 0.01050, 0.00360, -0.00360, -0.01050, -0.01765)   # ~7.1 mm spacing
STRING_X_BRIDGE = (0.02545, 0.01527, 0.00523, -0.00523, -0.01527, -0.02545)  # ~10.2 mm spacing
TUNING = ("E4", "B3", "G3", "D3", "A2", "E2")           # string 1 ... 6, standard tuning
OPEN_MIDI = (64, 59, 55, 50, 45, 40)                      # MIDI numbers of TUNING
PRESS_DISTANCE = 0.006           # a finger axis this close to a string presses it (paper Sec. 6)
PRESS_FRACTION = 0.5             # Eq. 4: p_{i,k} on the middle line of fret k (the authors' code: 0.3..0.5)

# Placement of the guitar in the world (reference §1.1): neck tilted ~26 deg up, fretboard toward +y (camera).
GUITAR_POS = (0.0, 0.0, 0.89)
GUITAR_QUAT = (0.5573, -0.18685, 0.57969, 0.56433)  # (w, x, y, z), normalized by MuJoCo on load

# Right-hand picking zone: strings between the end of the fretboard and the bridge.
BODY_TOP_Z = -0.0017             # top of the guitar body below the strings (reference §1.5)


def open_pitches() -> tuple[int, ...]:
    return OPEN_MIDI


def midi_to_hz(midi) -> np.ndarray:
    return 440.0 * 2.0 ** ((np.asarray(midi, dtype=np.float64) - 69.0) / 12.0)


@dataclasses.dataclass(frozen=True)
class Guitar:
    """Geometry of one guitar; `mirror=True` is the left-handed player's guitar (x negated)."""

    scale_length: float = SCALE_LENGTH
    n_frets: int = N_FRETS
    nut_y: float = NUT_Y
    string_z: float = STRING_Z
    fretboard_z: float = FRETBOARD_Z
    string_x_nut: tuple[float, ...] = STRING_X_NUT
    string_x_bridge: tuple[float, ...] = STRING_X_BRIDGE
    press_fraction: float = PRESS_FRACTION
    mirror: bool = False

    @property
    def sign(self) -> float:
        return -1.0 if self.mirror else 1.0

    @functools.cached_property
    def fret_y(self) -> np.ndarray:
        """(n_frets+1,) y of fret wire k by the equal-temperament rule; k = 0 is the nut."""
        k = np.arange(self.n_frets + 1, dtype=np.float64)
        return self.nut_y - self.scale_length * (1.0 - 2.0 ** (-k / 12.0))

    @property
    def bridge_y(self) -> float:
        return self.nut_y - self.scale_length

    @functools.cached_property
    def strings(self) -> np.ndarray:
        """(6, 2, 3) start (nut) and end (bridge) point of every string."""
        s = np.zeros((N_STRINGS, 2, 3))
        s[:, 0, 0] = self.sign * np.asarray(self.string_x_nut)
        s[:, 1, 0] = self.sign * np.asarray(self.string_x_bridge)
        s[:, 0, 1], s[:, 1, 1] = self.nut_y, self.bridge_y
        s[:, :, 2] = self.string_z
        return s

    def string_x(self, string: int, y) -> np.ndarray:
        """x of string (1-based) at guitar-frame y, by linear interpolation between nut and bridge."""
        a, b = self.strings[string - 1]
        t = (np.asarray(y, dtype=np.float64) - a[1]) / (b[1] - a[1])
        return a[0] + t * (b[0] - a[0])

    @functools.cached_property
    def target_points(self) -> np.ndarray:
        """(6, n_frets+1, 3) press target p_{i,k} (Eq. 4) on string i between wires k-1 and k; k = 0 is unused
        (open string) and holds the nut point."""
        y = self.fret_y.copy()
        y[1:] = (1 - self.press_fraction) * self.fret_y[1:] + self.press_fraction * self.fret_y[:-1]
        pts = np.zeros((N_STRINGS, self.n_frets + 1, 3))
        for i in range(N_STRINGS):
            pts[i, :, 0] = self.string_x(i + 1, y)
            pts[i, :, 1] = y
        pts[:, :, 2] = self.string_z
        return pts

    def pitch(self, string: int, fret: int) -> int:
        """MIDI pitch of string (1-based) pressed at fret (0 = open)."""
        if not 1 <= string <= N_STRINGS or not 0 <= fret <= self.n_frets:
            raise ValueError(f"no string {string} / fret {fret} on a {N_STRINGS}-string, {self.n_frets}-fret guitar")
        return OPEN_MIDI[string - 1] + fret

    @functools.cached_property
    def pitch_table(self) -> np.ndarray:
        """(6, n_frets+1) MIDI pitch of every (string, fret)."""
        return np.asarray(OPEN_MIDI)[:, None] + np.arange(self.n_frets + 1)[None, :]

    def frequency(self, string: int, fret: int) -> float:
        return float(midi_to_hz(self.pitch(string, fret)))

    def neck_half_width(self, y) -> np.ndarray:
        """Half-width of the tapered neck at y (linear from nut to fretboard end)."""
        t = (np.asarray(y, dtype=np.float64) - self.nut_y) / (NECK_END_Y - self.nut_y)
        return NECK_HALF_WIDTH[0] + t * (NECK_HALF_WIDTH[1] - NECK_HALF_WIDTH[0])


GUITAR = Guitar()
