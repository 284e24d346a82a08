"""MusicXML reader (via music21): `.musicxml` (plain XML) and `.mxl` (compressed), as MuseScore exports them.

* Part: music21 splits a part of several staves into one part per staff; parts are taken in file order and the
  `track` option (0-based, one per staff) picks one. By default the first *tab part* is read with its own strings
  and frets; a tab part is a staff with a TAB clef, or one whose every note carries `<technical><string>` and
  `<fret>` (string 1 = high E, as ours). Without a tab part, the first part with notes is read and strings and
  frets come from `fingering.assign_positions` (minimal hand travel), as for MIDI. MuseScore writes a guitar as
  one part of two staves (standard + TAB, the same notes twice) or as two parts; both give the TAB staff. Other
  parts are ignored.
* Tempo: the first metronome mark or `<sound tempo>` of the score (any part), else 120 BPM; later changes are
  ignored. Title: the work or movement title, else the file name.
* Time: every note keeps its written onset and length (all voices of the part together). The song is cut into slots
  at every onset and end of a written note; a slot lists the strings sounding in it, and a string still sounding
  from the slot before is marked `Effect.TIE` (a note held while others move, or a tied note). A slot where nothing
  sounds is a rest (all strings MUTE). Tied notes (tie start ... stop, same pitch, and same string on a tab) are
  one held note: the second and later are TIE. Grace notes, chord symbols and unpitched notes take no part;
  repeats are not expanded; hammer-ons, pull-offs and slides are read as plain notes.
* Pitch: with a tab part, string S and fret F must sound the note's pitch in standard tuning up to whole octaves
  (files differ on how they write the guitar's octave transposition); anything else means another tuning or a capo,
  which are refused. Without a tab part, sounding pitches are used (a part's `<transpose>` is applied); with
  `assign_positions` working slot by slot, a held note stays marked TIE only where it keeps its string and fret.

Errors (not MusicXML, a pitch the guitar cannot play, more notes than strings, two notes on one string at once, a
tempo out of range) raise `SongError` naming the file and "measure M" (the measure number the file gives), or
"line L, column C" where the XML cannot be parsed. Files are refused unread beyond `MAX_XML_BYTES` of XML (after
decompression for `.mxl`), and the song must keep the limits of `timing`.
"""
from __future__ import annotations

import bisect
import io
import math
import posixpath
import xml.etree.ElementTree as ET
import zipfile
from fractions import Fraction
from pathlib import Path

from dexguitar.music.fingering import FingeringError, assign_positions, pitch_name
from dexguitar.music.song import MUTE, Effect, Note, Song, SongError, read_bytes
from dexguitar.music.timing import check_tempo, check_timing
from dexguitar.world.guitar import N_FRETS, N_STRINGS, OPEN_MIDI

DEFAULT_TEMPO = 120.0
# MusicXML spends ~0.5 KB per note and staff: 8 MiB holds several thousand notes on two staves, far beyond a song.
MAX_XML_BYTES = 8 * 2**20
_STANDARD = " ".join(pitch_name(p) for p in OPEN_MIDI)


def _xml_bytes(path: Path) -> bytes:
    """The MusicXML text of a `.musicxml` file, or of the score inside a compressed `.mxl` (a zip file)."""
    data = read_bytes(path, MAX_XML_BYTES)
    if not data:
        raise SongError(path, None, "cannot read as MusicXML: the file is empty")
    if not data.startswith(b"PK"):
        return data
    try:
        with zipfile.ZipFile(io.BytesIO(data)) as z:
            name = _mxl_root(z)
            if name is None:
                raise SongError(path, None, "compressed MusicXML without a score inside")
            if z.getinfo(name).file_size > MAX_XML_BYTES:
                raise SongError(path, None, f"the score '{name}' in the archive is larger than {MAX_XML_BYTES} "
                                            f"bytes, the limit for MusicXML")
            with z.open(name) as f:
                xml = f.read(MAX_XML_BYTES + 1)
    except (zipfile.BadZipFile, zipfile.LargeZipFile, NotImplementedError, OSError, EOFError, KeyError) as e:
        raise SongError(path, None, f"cannot read as compressed MusicXML (.mxl): {e}") from None
    if len(xml) > MAX_XML_BYTES:
        raise SongError(path, None, f"the score in the archive is larger than {MAX_XML_BYTES} bytes, the limit "
                                    f"for MusicXML")
    return xml


def _mxl_root(z: zipfile.ZipFile) -> str | None:
    """The score's name in an .mxl: the first rootfile of META-INF/container.xml, else the first .xml/.musicxml."""
    names = z.namelist()
    if "META-INF/container.xml" in names:
        try:
            container = ET.fromstring(z.read("META-INF/container.xml"))
        except ET.ParseError:
            container = None
        if container is not None:
            for el in container.iter():
                full = el.get("full-path")
                if el.tag.rsplit("}", 1)[-1] == "rootfile" and full and full in names:
                    return full
    for name in names:
        if not name.startswith("META-INF/") and posixpath.splitext(name)[1].lower() in (".xml", ".musicxml"):
            return name
    return None


def _parse(path: Path, xml: bytes):
    """music21 Score of the MusicXML text (ElementTree reads the encoding the file declares)."""
    from music21.musicxml.xmlToM21 import MusicXMLImporter

    try:
        root = ET.fromstring(xml)
    except ET.ParseError as e:
        line, column = e.position
        msg = str(e).split(": line ")[0]
        raise SongError(path, f"line {line}, column {column + 1}", f"cannot read as MusicXML: {msg}") from None
    tag = root.tag.rsplit("}", 1)[-1]
    if tag != "score-partwise":
        what = "score-timewise MusicXML is not supported (MuseScore writes partwise)" if tag == "score-timewise" \
            else f"not MusicXML: the document is <{tag}>, not <score-partwise>"
        raise SongError(path, None, what)
    importer = MusicXMLImporter()
    try:
        importer.xmlRootToScore(root, importer.stream)
    except Exception as e:  # music21 raises many kinds on malformed scores
        raise SongError(path, None, f"cannot read as MusicXML: {type(e).__name__}: {e}") from None
    return importer.stream


class _Measures:
    """Time (whole notes from the part's start) -> the measure number the file gives."""

    def __init__(self, part):
        from music21 import stream

        self.starts, self.numbers = [], []
        for m in part.getElementsByClass(stream.Measure):
            self.starts.append(Fraction(m.offset) / 4)
            self.numbers.append(m.measureNumberWithSuffix())

    def at(self, t: Fraction) -> str:
        i = max(bisect.bisect_right(self.starts, t) - 1, 0)
        return f"measure {self.numbers[i]}" if self.numbers else "measure 1"


def _tab_pairs(el) -> list[tuple[int, int]] | None:
    """(string, fret) per note of a note or chord, in order of rising pitch, or None unless every note has both.

    music21 moves the string and fret marks of a chord's notes onto the chord, one note after the other in order
    of rising pitch; a single note keeps its own."""
    from music21 import articulations

    strings = [a.number for a in el.articulations if isinstance(a, articulations.StringIndication)]
    frets = [a.number for a in el.articulations if isinstance(a, articulations.FretIndication)]
    n = len(el.pitches)
    if len(strings) != n or len(frets) != n or any(x is None for x in strings + frets):
        return None
    return list(zip(strings, frets))


def _is_tab(part) -> bool:
    """A TAB clef, or string and fret on every note."""
    from music21 import clef

    if any(True for _ in part.recurse().getElementsByClass(clef.TabClef)):
        return True
    notes = list(_sounding_elements(part))
    return bool(notes) and all(_tab_pairs(el) is not None for _, el in notes)


def _sounding_elements(part):
    """(measure, note or chord) for every pitched, non-grace note of the part."""
    from music21 import chord, harmony, note, stream

    for m in part.getElementsByClass(stream.Measure):
        for el in m.recurse().notes:
            if isinstance(el, harmony.Harmony) or el.duration.isGrace or el.quarterLength == 0:
                continue
            if isinstance(el, (note.Note, chord.Chord)) and el.pitches:
                yield m, el


def _tempo(score, path: Path) -> float:
    from music21 import tempo

    best = None
    for mm in score.recurse().getElementsByClass(tempo.MetronomeMark):
        if mm.numberSounding is None and (mm.number is None or mm.numberImplicit):
            continue  # a tempo word ("Allegro") with a number music21 guessed
        bpm = mm.getQuarterBPM()
        if bpm is None:
            continue
        t = Fraction(mm.getOffsetInHierarchy(score))
        if best is None or t < best[0]:
            m = mm.getContextByClass("Measure")
            best = (t, float(bpm), f"measure {m.measureNumberWithSuffix()}" if m is not None else None)
    if best is None:
        return DEFAULT_TEMPO
    _, bpm, where = best
    if not math.isfinite(bpm):
        raise SongError(path, where, f"tempo {bpm} is not a number")
    try:
        check_tempo(bpm)
    except ValueError as e:
        raise SongError(path, where, str(e)) from None
    return bpm


class _Held:
    """One sounding note from its onset to its end, in whole notes; `ties` are the onsets of the notes tied to it."""

    __slots__ = ("start", "end", "pitch", "string", "fret", "ties")

    def __init__(self, start, end, pitch, string, fret):
        self.start, self.end, self.pitch, self.string, self.fret = start, end, pitch, string, fret
        self.ties: list[Fraction] = []


def _held_notes(part, path: Path, tab: bool) -> list[_Held]:
    """The part's notes with ties merged; on a tab, with their (0-based) string and fret, checked."""
    raw = []  # (start, end, pitch, string, fret, tie type)
    for m, el in _sounding_elements(part):
        start = (Fraction(m.offset) + Fraction(el.getOffsetInHierarchy(m))) / 4
        end = start + Fraction(el.quarterLength) / 4
        members = sorted(el.notes if el.isChord else [el], key=lambda n: n.pitch.ps)
        pairs = _tab_pairs(el) if tab else [(None, None)] * len(members)
        where = f"measure {m.measureNumberWithSuffix()}"
        if pairs is None:
            raise SongError(path, where, f"a note on the tab staff without string and fret "
                                         f"({' '.join(p.nameWithOctave for p in el.pitches)})")
        for n, (string, fret) in zip(members, pairs):
            pitch = int(round(n.pitch.ps))
            if tab:
                if not 1 <= string <= N_STRINGS:
                    raise SongError(path, where, f"string {string} does not exist (1..{N_STRINGS})")
                if not 0 <= fret <= N_FRETS:
                    raise SongError(path, where, f"string {string}: fret {fret} is outside 0..{N_FRETS}")
                sounds = OPEN_MIDI[string - 1] + fret
                if (sounds - pitch) % 12:
                    raise SongError(path, where, f"string {string}, fret {fret} sounds {pitch_name(sounds)} in "
                                                 f"standard tuning but the note is {n.pitch.nameWithOctave}; only "
                                                 f"standard tuning {_STANDARD} without capo is supported")
                string -= 1
            raw.append((start, end, pitch, string, fret, n.tie.type if n.tie is not None else None))
    raw.sort(key=lambda r: r[0])
    held: list[_Held] = []
    open_ties: dict[tuple, _Held] = {}
    for start, end, pitch, string, fret, tie in raw:
        key = (pitch, string)
        h = open_ties.pop(key, None) if tie in ("stop", "continue") else None
        if h is not None and h.end == start:
            h.end = end
            h.ties.append(start)
        else:
            h = _Held(start, end, pitch, string, fret)
            held.append(h)
        if tie in ("start", "continue"):
            open_ties[key] = h
    return held


def _part_end(part) -> Fraction:
    """End of the last note or rest of the part, in whole notes."""
    from music21 import stream

    end = Fraction(0)
    for m in part.getElementsByClass(stream.Measure):
        for el in m.recurse().notesAndRests:
            t = Fraction(m.offset) + Fraction(el.getOffsetInHierarchy(m)) + Fraction(el.quarterLength)
            end = max(end, t / 4)
    return end


def _slots(held: list[_Held], song_end: Fraction) -> list[tuple[Fraction, Fraction, list[_Held]]]:
    """(start, end, notes sounding) between consecutive onsets/ends of the notes (tied notes included), from 0 to
    the song's end."""
    bounds = {Fraction(0), song_end}
    for h in held:
        bounds.update((h.start, h.end, *h.ties))
    bounds = sorted(bounds)
    by_start = sorted(held, key=lambda h: h.start)
    out, active, k = [], [], 0
    for a, b in zip(bounds, bounds[1:]):
        while k < len(by_start) and by_start[k].start <= a:
            active.append(by_start[k])
            k += 1
        active = [h for h in active if h.end > a]
        out.append((a, b, list(active)))
    return out


def read_musicxml(path: str | Path, *, track: int | None = None) -> Song:
    """Read a MusicXML file (.musicxml or .mxl) into a `Song` (see the module docstring for every rule)."""
    path = Path(path)
    score = _parse(path, _xml_bytes(path))
    parts = list(score.parts)
    if track is not None:
        if isinstance(track, bool) or not isinstance(track, int) or not 0 <= track < len(parts):
            raise SongError(path, None, f"track {track!r} does not exist; the file has {len(parts)} staff part(s) "
                                        f"(0..{len(parts) - 1})")
        part = parts[track]
        if not any(True for _ in _sounding_elements(part)):
            raise SongError(path, f"track {track}", "this part has no notes")
        tab = _is_tab(part)
    else:
        with_notes = [p for p in parts if any(True for _ in _sounding_elements(p))]
        if not with_notes:
            raise SongError(path, None, "no notes in any part")
        tabs = [p for p in with_notes if _is_tab(p)]
        part = tabs[0] if tabs else with_notes[0]
        tab = bool(tabs)
    if not tab and not part.atSoundingPitch:
        part = part.toSoundingPitch(inPlace=False)
    bpm = _tempo(score, path)
    measures = _Measures(part)
    held = _held_notes(part, path, tab)
    slots = _slots(held, max(_part_end(part), max(h.end for h in held)))
    check_timing(bpm, [b - a for a, b, _ in slots], path)

    notes: list[Note] = []
    if tab:
        for a, b, active in slots:
            frets, effects = [MUTE] * N_STRINGS, [Effect.NONE] * N_STRINGS
            for h in active:
                if frets[h.string] != MUTE:
                    raise SongError(path, measures.at(a), f"two notes on string {h.string + 1} at once")
                frets[h.string] = h.fret
                if h.start < a:
                    effects[h.string] = Effect.TIE
            notes.append(Note(b - a, tuple(frets), tuple(effects)))
    else:
        try:
            positions = assign_positions([sorted({h.pitch for h in active}) for _, _, active in slots])
        except FingeringError as e:
            raise SongError(path, measures.at(slots[e.index][0]), str(e)) from None
        for k, (a, b, active) in enumerate(slots):
            frets = positions[k]
            effects = [Effect.NONE] * N_STRINGS
            for h in active:
                if h.start < a:
                    s = next(s for s in range(N_STRINGS) if frets[s] != MUTE and OPEN_MIDI[s] + frets[s] == h.pitch)
                    if positions[k - 1][s] == frets[s]:
                        effects[s] = Effect.TIE
            notes.append(Note(b - a, tuple(frets), tuple(effects)))
    title = (score.metadata.bestTitle or "").strip() if score.metadata is not None else ""
    return Song(tempo=bpm, notes=tuple(notes), title=title or path.stem)


__all__ = ["read_musicxml", "MAX_XML_BYTES"]
