"""Hear a performance: plucked-string synthesis (Karplus-Strong) driven by the detected picks and presses.

Why this design:
- Karplus-Strong is a delay loop with a lowpass in it, so a string's pitch is set by the loop delay. The loop here is
  y[n] = x[n] + g * (a0 y[n-N] + a1 y[n-N-1] + a2 y[n-N-2]): the two-point average (delay 1/2 sample) convolved
  with a linear-interpolation fractional delay d, total N + 1/2 + d = fs / f exactly, so the pitch is right to a
  few cents at every fret (an integer loop alone would be off by up to half a sample: ~1 % at 660 Hz).
- Every tap is at least N samples back, so the loop runs in blocks of N samples with numpy slices: no per-sample
  Python loop, no scipy.
- What sounds follows the simulation, not the tab: a pick of string i sounds the fret detected on it at that step
  (0 = open), a string rings until picked again or until its fret changes (hammer-on / pull-off / slide: restarted
  at the new pitch, softer), so a wrong press is heard as a wrong note.
"""
from __future__ import annotations

import wave
from collections.abc import Iterable
from pathlib import Path
from typing import NamedTuple

import numpy as np

from dexguitar.world.guitar import GUITAR, N_FRETS, N_STRINGS

SAMPLE_RATE = 44100


class Event(NamedTuple):
    """Something a string does at `time` seconds: string 1..6 starts sounding `fret` (0 open; -1 silences it) with
    `amplitude` (1 = a pick; legato restarts are softer)."""

    time: float
    string: int
    fret: int
    amplitude: float = 1.0


def pluck(frequency: float, seconds: float, sample_rate: int = SAMPLE_RATE, *, decay: float = 1.5,
          brightness: float = 0.5, amplitude: float = 1.0, seed: int = 0) -> np.ndarray:
    """One plucked string: float32 (round(seconds * sample_rate),) samples, peak about `amplitude`.

    frequency: Hz (fundamental, tuned exactly by the fractional loop delay); decay: seconds for the fundamental to
    fall by 1/e (made independent of pitch through the per-period loss); brightness in [0, 1]: 1 = white-noise
    excitation, lower = smoothed (a softer, rounder pick); seed: the excitation noise, for reproducible audio."""
    n_out = int(round(seconds * sample_rate))
    if n_out <= 0:
        return np.zeros(0, np.float32)
    period = sample_rate / float(frequency)
    if period < 3.0:
        raise ValueError(f"{frequency} Hz is too high for {sample_rate} Hz sampling")
    n = int(np.floor(period - 0.5))
    d = period - 0.5 - n                       # linear-interpolation fraction in [0, 1)
    taps = np.array([0.5 * (1 - d), 0.5, 0.5 * d])     # delays n, n+1, n+2 (average * interpolation)
    # The loop filter's magnitude at the fundamental, so the loss g gives exactly exp(-t / decay) per second.
    w = 2 * np.pi * frequency / sample_rate
    mag = abs(np.sum(taps * np.exp(-1j * w * np.arange(3))))
    g = np.exp(-1.0 / (frequency * decay)) / max(mag, 1e-6)
    g = min(g, 0.99999)

    rng = np.random.default_rng(seed)
    burst = rng.uniform(-1.0, 1.0, n + 2)
    smooth = float(np.clip(1.0 - brightness, 0.0, 0.95))
    for _ in range(2):                         # one-pole lowpass, forward and backward (no phase shift)
        for k in range(1, len(burst)):
            burst[k] = (1 - smooth) * burst[k] + smooth * burst[k - 1]
        burst = burst[::-1].copy()
    burst -= burst.mean()
    burst /= max(np.max(np.abs(burst)), 1e-9)

    total = n_out + n + 2
    y = np.zeros(total, np.float64)
    y[: n + 2] = burst                         # the excitation fills the first period (+2 for the taps)
    start = n + 2
    while start < total:                       # every block only reads samples >= n back: already computed
        stop = min(start + n, total)
        k = np.arange(start, stop)
        y[k] = g * (taps[0] * y[k - n] + taps[1] * y[k - n - 1] + taps[2] * y[k - n - 2])
        start = stop
    out = y[:n_out]
    peak = np.max(np.abs(out[: min(n_out, 4 * n + 4)]))
    return (amplitude * out / max(peak, 1e-9)).astype(np.float32)


def string_frequency(string: int, fret: int) -> float:
    """Hz of string 1..6 at fret (0 open), from the guitar's tuning (`world.guitar`)."""
    return GUITAR.frequency(string, int(np.clip(fret, 0, N_FRETS)))


def events_from_info(info, fps: float = 60.0, *, legato: bool = True, legato_seconds: float = 1.5,
                     min_hold: int = 2) -> list[Event]:
    """(time, string, fret, amplitude) events from per-step `press` (T, 6) and `picks` (T, 6) arrays.

    A pick at step t sounds at time (t + 1) / fps (the end of the control step in which the pick crossed the
    string) with the fret detected at that step. With `legato`, a change of the detected fret on a string that was
    picked less than `legato_seconds` ago sounds the new fret at amplitude 0.4 (a hammer-on / pull-off / slide);
    the new fret must hold `min_hold` steps, so a finger flickering at the detection threshold does not buzz."""
    press = np.asarray(info["press"] if isinstance(info, dict) else info[0]).astype(int)
    picks = np.asarray(info["picks"] if isinstance(info, dict) else info[1]).astype(bool)
    events: list[Event] = []
    for s in range(N_STRINGS):
        last_pick, current = None, None
        t = 0
        while t < len(press):
            if picks[t, s]:
                current, last_pick = int(press[t, s]), t
                events.append(Event((t + 1) / fps, s + 1, current, 1.0))
            elif (legato and last_pick is not None and press[t, s] != current
                  and (t - last_pick) / fps < legato_seconds
                  and np.all(press[t: t + min_hold, s] == press[t, s]) and t + min_hold <= len(press)):
                current = int(press[t, s])
                events.append(Event((t + 1) / fps, s + 1, current, 0.4))
            t += 1
    return sorted(events)


def render_audio(events: Iterable, seconds: float, sample_rate: int = SAMPLE_RATE, *, decay: float = 1.5,
                 gain: float = 0.3, fade: float = 0.005) -> np.ndarray:
    """Mix the notes of `events` ((time, string, fret[, amplitude]) tuples, e.g. `events_from_info`) into a float32
    mono track of `seconds`. A string sounds from its event until its next event (cut with a `fade` ramp, so no
    click); fret -1 only silences it. Notes are summed with `gain` each and soft-clipped (tanh): a strum of six
    strings stays below full scale and a quiet passage is not blown up by normalization."""
    n_total = int(round(seconds * sample_rate))
    out = np.zeros(n_total, np.float64)
    per_string: dict[int, list[Event]] = {}
    for e in events:
        e = Event(*e)
        per_string.setdefault(int(e.string), []).append(e)
    n_fade = max(1, int(fade * sample_rate))
    for string, evs in per_string.items():
        evs.sort(key=lambda e: e.time)
        for j, e in enumerate(evs):
            if e.fret < 0 or e.amplitude <= 0:
                continue
            begin = int(round(e.time * sample_rate))
            if begin >= n_total:
                continue
            end = n_total if j + 1 == len(evs) else min(n_total, int(round(evs[j + 1].time * sample_rate)))
            if end <= begin:
                continue
            seed = (string * 131 + int(e.fret) * 7 + j) & 0xFFFF
            note = pluck(string_frequency(string, e.fret), (end - begin) / sample_rate, sample_rate,
                         decay=decay, amplitude=e.amplitude, seed=seed).astype(np.float64)
            if end < n_total:                  # cut by the next event: ramp down instead of a click
                k = min(n_fade, len(note))
                note[-k:] *= np.linspace(1.0, 0.0, k)
            out[begin:begin + len(note)] += gain * note
    return np.tanh(out).astype(np.float32)


def write_wav(path, samples: np.ndarray, sample_rate: int = SAMPLE_RATE) -> Path:
    """16-bit PCM mono (or (n, channels)) WAV of float samples in [-1, 1], with the standard library's `wave`."""
    x = np.asarray(samples, np.float64)
    channels = 1 if x.ndim == 1 else x.shape[1]
    pcm = np.round(np.clip(x, -1.0, 1.0) * 32767.0).astype("<i2")
    path = Path(path)
    with wave.open(str(path), "wb") as w:
        w.setnchannels(channels)
        w.setsampwidth(2)
        w.setframerate(int(sample_rate))
        w.writeframes(pcm.tobytes())
    return path


def read_wav(path) -> tuple[np.ndarray, int]:
    """(float32 samples in [-1, 1], sample rate) of a 16-bit PCM WAV (mono: (n,), else (n, channels))."""
    with wave.open(str(path), "rb") as w:
        if w.getsampwidth() != 2:
            raise ValueError(f"{path}: expected 16-bit PCM, got {8 * w.getsampwidth()}-bit")
        channels, rate = w.getnchannels(), w.getframerate()
        data = np.frombuffer(w.readframes(w.getnframes()), "<i2").astype(np.float32) / 32767.0
    return (data if channels == 1 else data.reshape(-1, channels)), rate
