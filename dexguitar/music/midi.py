"""Standard MIDI file reader (via mido): notes -> quantized chords -> automatic fingering -> `Song`.

* Notes: note-on events (velocity > 0) of track `track` (0-based index into the file's tracks), or of all tracks
  merged when `track` is None; channel 10 (drums, mido channel 9) is always skipped. A note ends at its note-off
  (or note-on with velocity 0); a note never switched off ends at the end of its track.
* Tempo: the first `set_tempo` of the file (any track), else 120 BPM; the `tempo` option overrides it. Later tempo
  changes are ignored (quantization works in ticks, so they do not affect durations).
* Quantization: onsets snap to the nearest step of `grid` (a fraction of a whole note: "1/16" by default; triplet
  grids like "1/12" or "1/24" work too; "16" means "1/16"). Notes whose onsets snap to the same step form one
  chord (a pitch repeated within the step counts once).
* Durations: a chord lasts until the next chord's onset. Exception: when the chord's notes (their end snapped to
  the grid, at least one step after the onset) stop more than one grid step before the next onset, the chord keeps
  its own length and the gap becomes a rest note (all strings MUTE). The last chord lasts its own length (at least
  one step). Silence before the first note is dropped.
* Strings and frets come from `dexguitar.music.fingering.assign_positions` (minimal hand travel).

Errors (not a MIDI file, no notes, a pitch or chord the guitar cannot play) raise `SongError` with the file and
the position ("tick T, bar B"; bars counted from 1 using the file's time signatures, 4/4 by default; "byte N" where
the file cannot be decoded). Files larger than `song.MAX_FILE_BYTES` are refused unread, and the song must keep the
limits of `timing` (checked before the fingering search, which is the slow part).
"""
from __future__ import annotations

import io
import math
from fractions import Fraction
from pathlib import Path

from dexguitar.music.fingering import FingeringError, assign_positions
from dexguitar.music.song import MUTE, Note, Song, SongError, read_bytes
from dexguitar.music.timing import check_tempo, check_timing
from dexguitar.world.guitar import N_STRINGS

DRUM_CHANNEL = 9  # MIDI channel 10, numbered from 0 as mido does
DEFAULT_TEMPO = 120.0


def parse_grid(grid) -> Fraction:
    """"1/16" -> Fraction(1, 16); "16" -> 1/16; a Fraction passes through. Must be positive and at most 1."""
    if isinstance(grid, Fraction):
        value = grid
    else:
        text = str(grid).strip()
        try:
            value = Fraction(text) if "/" in text else 1 / Fraction(text)
        except (ValueError, ZeroDivisionError):
            raise ValueError(f"grid must look like '1/16', got {grid!r}") from None
    if not 0 < value <= 1:
        raise ValueError(f"grid must be a positive fraction of a whole note, at most 1, got {grid!r}")
    return value


class _Bars:
    """Tick -> bar number (from 1) following the file's time-signature changes."""

    def __init__(self, ticks_per_beat: int, signatures: list[tuple[int, int, int]]):
        self.tpb = ticks_per_beat
        sigs = sorted(signatures, key=lambda s: s[0])  # stable: the later event at one tick wins
        if not sigs or sigs[0][0] > 0:
            sigs.insert(0, (0, 4, 4))
        self.sigs = sigs

    def bar(self, tick: int) -> int:
        bar = 1
        for i, (t0, num, den) in enumerate(self.sigs):
            length = Fraction(4 * self.tpb * num, den)
            t1 = self.sigs[i + 1][0] if i + 1 < len(self.sigs) else None
            if t1 is None or tick < t1:
                return bar + int((tick - t0) // length)
            bar += math.ceil((t1 - t0) / length)  # a change in mid-bar starts a new bar
        return bar  # pragma: no cover (the last segment always returns)


def read_midi(path: str | Path, *, track: int | None = None, grid: str = "1/16", tempo: float | None = None
              ) -> Song:
    """Read a standard MIDI file into a `Song` (see the module docstring for every rule)."""
    import mido

    path = Path(path)
    try:
        step = parse_grid(grid)
    except ValueError as e:
        raise SongError(path, None, str(e)) from None
    if tempo is not None and not (isinstance(tempo, (int, float)) and math.isfinite(tempo) and tempo > 0):
        raise SongError(path, None, f"tempo must be a positive number, got {tempo!r}")
    data = read_bytes(path)
    if not data:
        raise SongError(path, None, "cannot read as a MIDI file: the file is empty")
    stream = io.BytesIO(data)
    try:
        mid = mido.MidiFile(file=stream)
    except EOFError:
        raise SongError(path, f"byte {len(data)}", "cannot read as a MIDI file: it ends in the middle of the MIDI "
                                                   "data (truncated?)") from None
    except Exception as e:  # mido raises OSError, KeyError, ValueError ... on bad input
        raise SongError(path, f"byte {stream.tell()}", f"cannot read as a MIDI file: {type(e).__name__}: {e}"
                        ) from None
    tpb = mid.ticks_per_beat
    if not isinstance(tpb, int) or tpb <= 0:
        raise SongError(path, None, f"unsupported time division (ticks per beat {tpb!r})")
    if track is not None and (isinstance(track, bool) or not isinstance(track, int)
                              or not 0 <= track < len(mid.tracks)):
        raise SongError(path, None, f"track {track!r} does not exist; the file has {len(mid.tracks)} track(s)")

    first_tempo: tuple[int, int] | None = None  # (tick, microseconds per beat)
    signatures: list[tuple[int, int, int]] = []
    notes: list[tuple[int, int, int]] = []      # (start tick, end tick, pitch)
    for t_index, mtrack in enumerate(mid.tracks):
        tick = 0
        selected = track is None or t_index == track
        open_notes: dict[tuple[int, int], list[int]] = {}
        for msg in mtrack:
            tick += msg.time
            if msg.type == "set_tempo":
                if first_tempo is None or tick < first_tempo[0]:
                    first_tempo = (tick, msg.tempo)
            elif msg.type == "time_signature" and msg.numerator > 0:   # a 0/x bar would have no length
                signatures.append((tick, msg.numerator, msg.denominator))
            elif not selected or msg.type not in ("note_on", "note_off") or msg.channel == DRUM_CHANNEL:
                continue
            elif msg.type == "note_on" and msg.velocity > 0:
                open_notes.setdefault((msg.channel, msg.note), []).append(tick)
            else:
                starts = open_notes.get((msg.channel, msg.note))
                if starts:
                    notes.append((starts.pop(0), tick, msg.note))
        for (_, pitch), starts in open_notes.items():
            notes.extend((s, tick, pitch) for s in starts)
    if not notes:
        where = f"track {track}" if track is not None else None
        raise SongError(path, where, "no notes (drum channel 10 is ignored)")

    bars = _Bars(tpb, signatures)
    if tempo is not None:
        bpm, tempo_at = float(tempo), None
    elif first_tempo is not None:
        bpm = mido.tempo2bpm(max(first_tempo[1], 1))                  # 0 us per beat: refused just below
        tempo_at = f"tick {first_tempo[0]}, bar {bars.bar(first_tempo[0])}"
    else:
        bpm, tempo_at = DEFAULT_TEMPO, None
    try:
        check_tempo(bpm)
    except ValueError as e:
        raise SongError(path, tempo_at, str(e) if tempo is None else f"tempo option: {e}") from None
    step_ticks = step * 4 * tpb

    def snap(tick: int) -> int:
        return math.floor(Fraction(tick) / step_ticks + Fraction(1, 2))

    chords: dict[int, dict] = {}  # onset step -> {"pitches", "end", "tick"}
    for start, end, pitch in sorted(notes):
        q = snap(start)
        c = chords.setdefault(q, {"pitches": set(), "end": q + 1, "tick": start})
        c["pitches"].add(pitch)
        c["end"] = max(c["end"], snap(end), q + 1)
    onsets = sorted(chords)
    plan = []  # (duration in grid steps, index into `onsets` of the chord, or None for a rest)
    for k, q in enumerate(onsets):
        end = chords[q]["end"]
        nxt = onsets[k + 1] if k + 1 < len(onsets) else None
        if nxt is not None and nxt - end > 1:
            plan += [(end - q, k), (nxt - end, None)]
        else:
            plan.append(((end if nxt is None else nxt) - q, k))
    check_timing(bpm, [d * step for d, _ in plan], path)

    try:
        frets = assign_positions([sorted(chords[q]["pitches"]) for q in onsets])
    except FingeringError as e:
        tick = chords[onsets[e.index]]["tick"]
        raise SongError(path, f"tick {tick}, bar {bars.bar(tick)}", str(e)) from None

    out = [Note(d * step, frets[k] if k is not None else (MUTE,) * N_STRINGS) for d, k in plan]
    return Song(tempo=bpm, notes=tuple(out), title=path.stem)
