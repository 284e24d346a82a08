"""Guitar Pro 3/4/5 reader (via PyGuitarPro's `guitarpro.parse`).

What is read, and how:
* track: the one at index `track` (0-based, as in `song.tracks`), else the first non-percussion 6-string track in
  standard tuning (E4 B3 G3 D3 A2 E2). Another tuning raises `SongError` (our guitar is in standard tuning). A capo
  (the track's fret offset) is added to every fret so the sounding pitches stay right.
* tempo: the song's initial tempo (later tempo changes are ignored); title: the song title, else the file name.
* each beat of the *first voice* becomes one `Note`, in measure order (repeats are not expanded; grace notes,
  bends, harmonics, chord diagrams and other ornaments are ignored). Beats marked "empty" take no time and are
  skipped; a measure without any beat in the first voice becomes a rest of the measure's length.
* duration = 1/value, times 3/2 when dotted, times `times/enters` for a tuplet (a triplet eighth = 1/12): exact.
* rest beats -> an all-MUTE note; notes -> fret `value` on string `string` (GP numbers strings from 1 = highest,
  like we do); dead notes -> MUTE; tied notes -> `Effect.TIE` (PyGuitarPro fills in the tied fret).
* legato: Guitar Pro puts the hammer-on/pull-off mark on the note the legato starts *from*, and slides
  (shift/legato "slide to") likewise on the origin note. The *next* note on the same string therefore gets
  `Effect.HAMMER` (its fret is higher than the origin's) or `Effect.PULL` (otherwise), or `Effect.SLIDE`
  (slides win over hammer marks). A rest in between cancels a pending legato.

Errors (unreadable file, no suitable track, fret > 22, ...) raise `SongError` with the file and
"track T, measure M, beat B" (T 0-based like the `track` option, M and B 1-based as Guitar Pro shows them), or
"byte N" where the file cannot be decoded. Files larger than `song.MAX_FILE_BYTES` are refused unread, and the song
must keep the limits of `timing` (those errors name "track T, note I", I counting every beat read, 0-based).
"""
from __future__ import annotations

import io
import struct
from fractions import Fraction
from pathlib import Path

from dexguitar.music.song import MUTE, Effect, Note, Song, SongError, read_bytes
from dexguitar.music.timing import validate
from dexguitar.world.guitar import N_FRETS, N_STRINGS, OPEN_MIDI

_WHOLE_TICKS = 3840  # PyGuitarPro: a quarter note is 960 ticks


def _is_standard(track) -> bool:
    return sorted((s.number, s.value) for s in track.strings) == [(i + 1, p) for i, p in enumerate(OPEN_MIDI)]


def _tuning_text(track) -> str:
    return " ".join(str(s) for s in sorted(track.strings, key=lambda s: s.number))


def _pick_track(gp_song, path, track):
    tracks = gp_song.tracks
    if track is not None:
        if isinstance(track, bool) or not isinstance(track, int) or not 0 <= track < len(tracks):
            raise SongError(path, None, f"track {track!r} does not exist; the file has {len(tracks)} track(s) "
                                        f"(0..{len(tracks) - 1})")
        t = tracks[track]
        where = f"track {track}"
        if t.isPercussionTrack:
            raise SongError(path, where, f"'{t.name}' is a percussion track")
        if len(t.strings) != N_STRINGS:
            raise SongError(path, where, f"'{t.name}' has {len(t.strings)} strings; a 6-string guitar is needed")
        if not _is_standard(t):
            raise SongError(path, where, f"'{t.name}' is tuned {_tuning_text(t)}; only standard tuning "
                                         f"E4 B3 G3 D3 A2 E2 is supported")
        return track, t
    six = [i for i, t in enumerate(tracks) if not t.isPercussionTrack and len(t.strings) == N_STRINGS]
    if not six:
        names = ", ".join(f"{i}: '{t.name}' ({len(t.strings)} strings)" for i, t in enumerate(tracks))
        raise SongError(path, None, f"no 6-string guitar track (tracks: {names})")
    for i in six:
        if _is_standard(tracks[i]):
            return i, tracks[i]
    t = tracks[six[0]]
    raise SongError(path, f"track {six[0]}", f"'{t.name}' is tuned {_tuning_text(t)}; only standard tuning "
                                             f"E4 B3 G3 D3 A2 E2 is supported")


def beat_duration(duration) -> Fraction:
    """Exact length of a PyGuitarPro `Duration` as a fraction of a whole note."""
    d = Fraction(1, duration.value)
    if duration.isDotted:
        d *= Fraction(3, 2)
    tuplet = duration.tuplet
    return d * Fraction(tuplet.times, tuplet.enters)


def read_guitarpro(path: str | Path, *, track: int | None = None) -> Song:
    """Read a Guitar Pro 3/4/5 file into a `Song` (see the module docstring for the mapping)."""
    import guitarpro

    path = Path(path)
    data = read_bytes(path)
    if not data:
        raise SongError(path, None, "cannot read as Guitar Pro 3/4/5: the file is empty")
    stream = io.BytesIO(data)
    try:
        gp_song = guitarpro.parse(stream)
    except Exception as e:  # PyGuitarPro raises many kinds on bad input, some wrapped in a GPException
        if isinstance(e, struct.error) or isinstance(e.__cause__, struct.error):   # it read past the end
            raise SongError(path, f"byte {len(data)}", "cannot read as Guitar Pro 3/4/5: the file ends in the middle "
                                                       "of the song data (truncated?)") from None
        raise SongError(path, f"byte {stream.tell()}", f"cannot read as Guitar Pro 3/4/5: {e}") from None
    t_index, gp_track = _pick_track(gp_song, path, track)
    capo = int(gp_track.offset or 0)

    notes: list[Note] = []
    pending: dict[int, tuple[str, int]] = {}  # string index -> ("hammer" | "slide", origin fret)
    for m_index, measure in enumerate(gp_track.measures):
        m_number = m_index + 1
        beats = [(b_index + 1, b) for b_index, b in enumerate(measure.voices[0].beats)
                 if b.status != guitarpro.BeatStatus.empty]
        if not beats:
            length = Fraction(measure.header.length, _WHOLE_TICKS)
            if length > 0:
                notes.append(Note(length, (MUTE,) * N_STRINGS))
            pending.clear()
            continue
        for b_number, beat in beats:
            where = f"track {t_index}, measure {m_number}, beat {b_number}"
            try:
                duration = beat_duration(beat.duration)
            except (ZeroDivisionError, TypeError, AttributeError) as e:
                raise SongError(path, where, f"bad duration: {e}") from None
            if duration <= 0:
                raise SongError(path, where, f"bad duration {duration} (a tuplet with a negative count?)")
            frets = [MUTE] * N_STRINGS
            effects = [Effect.NONE] * N_STRINGS
            origins: dict[int, tuple[str, int]] = {}
            for gp_note in beat.notes if beat.status != guitarpro.BeatStatus.rest else ():
                if gp_note.type == guitarpro.NoteType.rest:
                    continue
                s = gp_note.string - 1
                if not 0 <= s < N_STRINGS:
                    raise SongError(path, where, f"string {gp_note.string} does not exist (1..{N_STRINGS})")
                if frets[s] != MUTE:
                    raise SongError(path, where, f"two notes on string {gp_note.string}")
                if gp_note.type == guitarpro.NoteType.dead:
                    pending.pop(s, None)
                    continue
                fret = int(gp_note.value)
                if gp_note.type == guitarpro.NoteType.tie and fret < 0:
                    raise SongError(path, where, f"tied note on string {gp_note.string} follows no note")
                fret += capo
                if not 0 <= fret <= N_FRETS:
                    extra = f" (fret {gp_note.value} + capo {capo})" if capo else ""
                    raise SongError(path, where, f"string {gp_note.string}: fret {fret}{extra} is outside "
                                                 f"0..{N_FRETS}")
                frets[s] = fret
                origin = pending.pop(s, None)
                if gp_note.type == guitarpro.NoteType.tie:
                    effects[s] = Effect.TIE
                elif origin is not None:
                    kind, origin_fret = origin
                    if kind == "slide":
                        effects[s] = Effect.SLIDE
                    else:
                        effects[s] = Effect.HAMMER if fret > origin_fret else Effect.PULL
                effect = gp_note.effect
                if any(sl in (guitarpro.SlideType.shiftSlideTo, guitarpro.SlideType.legatoSlideTo)
                       for sl in (effect.slides or ())):
                    origins[s] = ("slide", fret)
                elif effect.hammer:
                    origins[s] = ("hammer", fret)
            if all(f == MUTE for f in frets):
                pending.clear()
            pending.update(origins)
            notes.append(Note(duration, tuple(frets), tuple(effects)))
    if not notes:
        raise SongError(path, f"track {t_index}", f"'{gp_track.name}' has no beats")
    title = gp_song.title.strip() if gp_song.title else ""
    try:
        song = Song(tempo=gp_song.tempo, notes=tuple(notes), title=title or path.stem)
    except ValueError as e:
        raise SongError(path, None, str(e)) from None
    return validate(song, path, f"track {t_index}")
