"""The authors' JSON tab format (reader and writer).

A file holds a list of tracks; a track is `{"tempo": BPM, "notes": [note, ...]}` and a note is
`{"t": duration, "effects": {...}, "frets": [6 ints]}`:

* `frets[0]` is string 1 (high E); -1 = string not played, 0 = open, k >= 1 = fret k (k <= 22).
* `t` is a fraction of a whole note: `"a/b"` (a and b may be decimals: the authors write a triplet eighth as
  `"0.3333333/8"`; such values are snapped to the nearest fraction with denominator <= 192, i.e. 1/24, and rejected
  when that fraction is more than 1e-4 (relative) away), `"n"` (n whole notes) or a JSON number (whole notes).
* `effects` (all optional, each a 6-vector indexed like `frets`):
    - `"tied"`: 0/1 -> `Effect.TIE` (the string keeps sounding from the previous note);
    - `"hammer/pull"`: 0/1 -> `Effect.HAMMER` when the string's fret is higher than in the previous note that
      played that string, else `Effect.PULL` (also when no earlier note played it and the fret is 0);
    - `"chords"`: frets of the left-hand chord hint (-1 = string not in the chord) -> `Note.chord`.
  Unknown effect keys are rejected (a typo would otherwise silently change the song); an effect flag on a string
  the note does not play is rejected too.

Extension: a track may carry `"title"`; the writer always writes it so that titles survive a round trip; without
it the reader uses the file name (without suffix) as the title.

Tracks: `track` picks one (0-based). Without it a file of one track is read; a file of several has all of them
read (a bad track is refused, naming it) and is refused, listing its tracks, unless they hold the same song.

Reading: the file may start with a UTF-8 byte-order mark; it is refused when larger than `song.MAX_FILE_BYTES`, and
the song must keep the limits of `timing` (tempo, shortest note, length).

Writing (only to a `.json` path): the format has no slide, so `Effect.SLIDE` is written as `"hammer/pull"` (a legato
note sounded by the left hand) and reads back as HAMMER or PULL. Durations are written exactly as `"a/b"`; the tempo
as an integer when it is whole. Effects on strings that do not sound are dropped. For every other song
`read(write(song)) == song` (provided its HAMMER/PULL flags agree with the fret direction, which is how the reader
decides between them).
"""
from __future__ import annotations

import json
import math
from fractions import Fraction
from pathlib import Path

from dexguitar.errors import UserError
from dexguitar.music.song import MUTE, Effect, Note, Song, SongError, read_bytes
from dexguitar.music.timing import check_tempo, validate
from dexguitar.world.guitar import N_FRETS, N_STRINGS

MAX_DENOMINATOR = 192   # decimal durations snap to a fraction with at most this denominator
SNAP_TOLERANCE = 1e-4   # ... and must lie this close to it (relative), else the duration is rejected
_KNOWN_EFFECTS = ("tied", "hammer/pull", "chords")


def _is_int(x) -> bool:
    return isinstance(x, int) and not isinstance(x, bool)


def _is_number(x) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)


def parse_duration(t) -> Fraction:
    """`t` field -> exact fraction of a whole note. Raises ValueError with a short reason."""
    if _is_int(t):
        value = Fraction(t)
    elif _is_number(t):
        if not math.isfinite(t):
            raise ValueError(f"'t' must be finite, got {t!r}")
        value = _snap(Fraction(repr(t)), t)
    elif isinstance(t, str):
        text = t.strip()
        num, sep, den = text.partition("/")
        try:
            a = Fraction(num.strip())
            b = Fraction(den.strip()) if sep else Fraction(1)
        except (ValueError, ZeroDivisionError):
            raise ValueError(f"'t' must look like 'a/b', 'n' or a number, got {t!r}") from None
        if b == 0:
            raise ValueError(f"'t' has a zero denominator: {t!r}")
        value = a / b
        if value.denominator > 1 and (a.denominator > 1 or b.denominator > 1):  # decimals: snap
            value = _snap(value, t)
    else:
        raise ValueError(f"'t' must be a string or a number, got {type(t).__name__}")
    if value <= 0:
        raise ValueError(f"'t' must be positive, got {t!r}")
    return value


def _snap(value: Fraction, shown) -> Fraction:
    snapped = value.limit_denominator(MAX_DENOMINATOR)
    if value == 0 or abs(snapped - value) > SNAP_TOLERANCE * abs(value):
        raise ValueError(f"'t' = {shown!r} is not close to a fraction with denominator <= {MAX_DENOMINATOR}")
    return snapped


def _six(value, what: str, lo: int, hi: int) -> tuple[int, ...]:
    if not isinstance(value, list) or len(value) != N_STRINGS or not all(_is_int(v) for v in value):
        raise ValueError(f"'{what}' must be {N_STRINGS} integers, got {json.dumps(value)}")
    for i, v in enumerate(value):
        if not lo <= v <= hi:
            raise ValueError(f"'{what}' string {i + 1}: {v} is outside {lo}..{hi}")
    return tuple(value)


def _flags(value, what: str) -> tuple[bool, ...]:
    if (not isinstance(value, list) or len(value) != N_STRINGS
            or not all(isinstance(v, (int, bool)) and v in (0, 1) for v in value)):
        raise ValueError(f"'{what}' must be {N_STRINGS} values 0 or 1, got {json.dumps(value)}")
    return tuple(bool(v) for v in value)


def _parse_track(data, path, t: int) -> Song:
    where = f"track {t}"
    if not isinstance(data, dict):
        raise SongError(path, where, f"a track must be an object with 'tempo' and 'notes', got {type(data).__name__}")
    for key in ("tempo", "notes"):
        if key not in data:
            raise SongError(path, where, f"missing key '{key}'")
    tempo = data["tempo"]
    if not _is_number(tempo):
        raise SongError(path, where, f"'tempo' must be a number of beats per minute, got {tempo!r}")
    try:
        check_tempo(tempo)
    except ValueError as e:
        raise SongError(path, where, f"'tempo': {e}") from None
    notes_in = data["notes"]
    if not isinstance(notes_in, list):
        raise SongError(path, where, "'notes' must be a list")
    if not notes_in:
        raise SongError(path, where, "'notes' is empty")
    title = data.get("title", Path(path).stem if path is not None else "")
    if not isinstance(title, str):
        raise SongError(path, where, "'title' must be a string")

    last_fret = [None] * N_STRINGS  # fret of the previous note that played each string
    notes = []
    for i, raw in enumerate(notes_in):
        try:
            note = _parse_note(raw, last_fret)
        except ValueError as e:
            raise SongError(path, f"{where}, note {i}", str(e)) from None
        notes.append(note)
        for s, f in enumerate(note.frets):
            if f != MUTE:
                last_fret[s] = f
    return validate(Song(tempo=tempo, notes=tuple(notes), title=title), path, where)


def _parse_note(raw, last_fret) -> Note:
    if not isinstance(raw, dict):
        raise ValueError(f"a note must be an object, got {type(raw).__name__}")
    for key in ("t", "frets"):
        if key not in raw:
            raise ValueError(f"missing key '{key}'")
    duration = parse_duration(raw["t"])
    frets = _six(raw["frets"], "frets", MUTE, N_FRETS)
    effects_in = raw.get("effects", {})
    if effects_in is None:
        effects_in = {}
    if not isinstance(effects_in, dict):
        raise ValueError("'effects' must be an object")
    unknown = sorted(set(effects_in) - set(_KNOWN_EFFECTS))
    if unknown:
        raise ValueError(f"unknown effect {unknown[0]!r}; known: {', '.join(_KNOWN_EFFECTS)}")
    effects = [Effect.NONE] * N_STRINGS
    for key in ("tied", "hammer/pull"):
        if key not in effects_in:
            continue
        for s, on in enumerate(_flags(effects_in[key], key)):
            if not on:
                continue
            if frets[s] == MUTE:
                raise ValueError(f"'{key}' marks string {s + 1}, which the note does not play")
            if key == "tied":
                effects[s] |= Effect.TIE
            else:
                prev = last_fret[s] if last_fret[s] is not None else 0
                effects[s] |= Effect.HAMMER if frets[s] > prev else Effect.PULL
    chord = _six(effects_in["chords"], "chords", MUTE, N_FRETS) if "chords" in effects_in else None
    return Note(duration, frets, tuple(effects), chord)


def read_json_tab(path: str | Path, *, track: int | None = None) -> Song:
    """Read one track (index `track`, 0-based) of an authors' JSON tab file into a `Song`. Without `track`, a file
    of several tracks has every track read (a bad one is refused, naming it) and is refused, listing them, unless
    they all hold the same song: which track to play is the user's choice, not the first one's by default.

    Errors raise `SongError` naming the file and the position ("line L, column C" for invalid JSON,
    "track T, note N" with 0-based indices for bad content).
    """
    path = Path(path)
    raw = read_bytes(path)
    try:
        text = raw.decode("utf-8-sig")
    except UnicodeDecodeError as e:
        raise SongError(path, f"byte {e.start}", f"not UTF-8 text ({e.reason}): a JSON tab is a text file") from None
    try:
        data = json.loads(text)
    except json.JSONDecodeError as e:
        raise SongError(path, f"line {e.lineno}, column {e.colno}", f"not valid JSON: {e.msg}") from None
    except RecursionError:
        raise SongError(path, None, "not a tab: JSON nested too deeply (a tab is a list of tracks, each with a list "
                                    "of notes)") from None
    except ValueError as e:      # e.g. an integer of more than 4300 digits
        raise SongError(path, None, f"not valid JSON: {e}") from None
    if isinstance(data, dict):  # lenient: a single track object instead of a list of tracks
        data = [data]
    if not isinstance(data, list):
        raise SongError(path, None, f"expected a list of tracks, got {type(data).__name__}")
    if not data:
        raise SongError(path, None, "the file holds no tracks")
    if track is None:
        songs = [_parse_track(t, path, i) for i, t in enumerate(data)]
        if any((s.tempo, s.notes) != (songs[0].tempo, songs[0].notes) for s in songs[1:]):
            listed = "; ".join(f"{i}: '{s.title}', {s.tempo:g} BPM, {len(s.notes)} note{'s' * (len(s.notes) != 1)}"
                               for i, s in enumerate(songs[:8])) + ("; ..." if len(songs) > 8 else "")
            raise SongError(path, None, f"{len(songs)} different tracks ({listed}): choose one with --track N "
                                        f"(0..{len(songs) - 1})")
        return songs[0]
    if not _is_int(track) or not 0 <= track < len(data):
        raise SongError(path, None, f"track {track!r} does not exist; the file has {len(data)} track(s) "
                                    f"(0..{len(data) - 1})")
    return _parse_track(data[track], path, track)


def _duration_text(d: Fraction) -> str:
    d = Fraction(d)
    return f"{d.numerator}/{d.denominator}"


def _note_json(note: Note) -> dict:
    effects: dict[str, list[int]] = {}
    sounding = [f != MUTE for f in note.frets]
    tied = [int(bool(e & Effect.TIE) and on) for e, on in zip(note.effects, sounding)]
    legato = [int(bool(e & (Effect.HAMMER | Effect.PULL | Effect.SLIDE)) and on)
              for e, on in zip(note.effects, sounding)]
    if any(tied):
        effects["tied"] = tied
    if any(legato):
        effects["hammer/pull"] = legato
    if note.chord is not None:
        effects["chords"] = list(note.chord)
    return {"t": _duration_text(note.duration), "effects": effects, "frets": list(note.frets)}


def dumps_json_tab(song: Song) -> str:
    """The JSON text `write_json_tab` writes: one track, one note per line (like the authors' files)."""
    tempo = float(song.tempo)
    tempo = int(tempo) if tempo.is_integer() else tempo
    head = f'    {{\n        "tempo": {json.dumps(tempo)},\n        "title": {json.dumps(song.title)},\n'
    lines = ",\n".join("            " + json.dumps(_note_json(n)) for n in song.notes)
    return f'[\n{head}        "notes": [\n{lines}\n        ]\n    }}\n]\n'


def write_json_tab(song: Song, path: str | Path) -> None:
    """Write `song` as a one-track JSON tab file (see the module docstring for the mapping). The path must end in
    `.json`: JSON in a `.txt` would be read back as an ASCII tab."""
    path = Path(path)
    if path.suffix.lower() != ".json":
        raise UserError(f"{path}: can only write the JSON tab format, to a file ending in .json "
                        f"(got '{path.suffix or 'no suffix'}')")
    path.write_text(dumps_json_tab(song), encoding="utf-8")
