"""MusicXML reader: files written by music21 the way MuseScore writes a guitar (notes an octave above sounding
pitch with `<transpose>`, standard + TAB staff in one part), read back and compared with a JSON tab written by hand."""
import json
import xml.etree.ElementTree as ET
import zipfile

import pytest

from dexguitar.music import load_song
from dexguitar.music.song import SongError
from dexguitar.music.tab_json import read_json_tab


# The phrase, in sounding pitches: E2 | G3 C4 E4 chord | rest | A3 tied over the bar line into a half | B3 half.
# On the tab, B3 is string 3, fret 4 (the fingering search would take the open B string instead).
TAB_FRETS = {"E3": (6, 0), "G4": (3, 0), "C5": (2, 1), "E5": (1, 0), "A4": (3, 2), "B4": (3, 4)}  # written pitch


def expected(last_frets):
    return [{"tempo": 90, "title": "Phrase", "notes": [
        {"t": "1/4", "frets": [-1, -1, -1, -1, -1, 0]},
        {"t": "1/4", "frets": [0, 1, 0, -1, -1, -1]},
        {"t": "1/4", "frets": [-1, -1, -1, -1, -1, -1]},
        {"t": "1/4", "frets": [-1, -1, 2, -1, -1, -1]},
        {"t": "1/2", "frets": [-1, -1, 2, -1, -1, -1], "effects": {"tied": [0, 0, 1, 0, 0, 0]}},
        {"t": "1/2", "frets": last_frets},
    ]}]


def staff(last="B3"):
    """One guitar staff of the phrase, written an octave above sounding pitch as MuseScore writes a guitar."""
    from music21 import chord, instrument, interval, meter, note, stream, tie

    def n(name, ql=1.0):
        x = note.Note(name, quarterLength=ql)
        x.pitch.midi += 12
        return x

    part = stream.PartStaff()
    guitar = instrument.Guitar()
    guitar.transposition = interval.Interval("P-8")
    part.insert(0, guitar)
    m1, m2 = stream.Measure(number=1), stream.Measure(number=2)
    m1.append(meter.TimeSignature("4/4"))
    m1.append(n("E2"))
    m1.append(chord.Chord([n("G3"), n("C4"), n("E4")]))
    m1.append(note.Rest(quarterLength=1))
    a1, a2 = n("A3"), n("A3", 2)
    a1.tie, a2.tie = tie.Tie("start"), tie.Tie("stop")
    m1.append(a1)
    m2.append([a2, n(last, 2)])
    part.append([m1, m2])
    part.atSoundingPitch = False
    return part


def score(*staves):
    from music21 import clef, layout, metadata, stream, tempo

    s = stream.Score()
    s.metadata = metadata.Metadata(title="Phrase")
    staves[0].measure(1).insert(0, clef.Treble8vbClef())
    staves[0].measure(1).insert(0, tempo.MetronomeMark(number=90))
    if len(staves) == 2:
        staves[1].measure(1).insert(0, clef.TabClef())
    for p in staves:
        s.insert(0, p)
    if len(staves) == 2:
        s.insert(0, layout.StaffGroup(list(staves), symbol="brace"))
    return s


def add_frets(xml_path, frets):
    """music21 writes the string and fret marks of a chord on its first note only, so the tab staff's marks are
    added to the file directly: every note of staff 2 gets those of its written pitch."""
    tree = ET.parse(xml_path)
    for el in tree.iter("note"):
        pitch = el.find("pitch")
        if el.findtext("staff") != "2" or pitch is None:
            continue
        string, fret = frets[pitch.findtext("step") + pitch.findtext("octave")]
        notations = el.find("notations")
        if notations is None:
            notations = ET.SubElement(el, "notations")
        technical = ET.SubElement(notations, "technical")
        ET.SubElement(technical, "string").text = str(string)
        ET.SubElement(technical, "fret").text = str(fret)
    tree.write(xml_path, encoding="UTF-8", xml_declaration=True)


def write_mxl(xml_path, mxl_path):
    """A compressed MusicXML file: the score plus META-INF/container.xml naming it."""
    container = ('<?xml version="1.0" encoding="UTF-8"?><container><rootfiles>'
                 '<rootfile full-path="score.musicxml"/></rootfiles></container>')
    with zipfile.ZipFile(mxl_path, "w", zipfile.ZIP_DEFLATED) as z:
        z.writestr("META-INF/container.xml", container)
        z.write(xml_path, "score.musicxml")


def write_tab_files(tmp_path, frets=TAB_FRETS):
    xml = tmp_path / "tab.musicxml"
    score(staff(), staff()).write("musicxml", fp=str(xml))
    add_frets(xml, frets)
    write_mxl(xml, tmp_path / "tab.mxl")
    return xml, tmp_path / "tab.mxl"


def json_song(tmp_path, tracks):
    path = tmp_path / "expected.json"
    path.write_text(json.dumps(tracks))
    return read_json_tab(path)


def assert_same(song, want):
    assert song.tempo == want.tempo
    assert song.title == want.title
    assert [(n.duration, n.frets, n.effects) for n in song.notes] == \
        [(n.duration, n.frets, n.effects) for n in want.notes]


def test_tab_staff_gives_strings_and_frets(tmp_path):
    want = json_song(tmp_path, expected([-1, -1, 4, -1, -1, -1]))
    for path in write_tab_files(tmp_path):
        assert_same(load_song(path), want)
    # Staff 0 of the same part is the standard staff: its notes get the fingering search's strings (open B).
    plain = json_song(tmp_path, expected([-1, 0, -1, -1, -1, -1]))
    assert_same(load_song(tmp_path / "tab.musicxml", track=0), plain)


def test_without_tab_the_fingering_is_assigned(tmp_path):
    # The fingering search (least hand travel) plays the chord in first position and B3 on the open B string.
    want = json_song(tmp_path, expected([-1, 0, -1, -1, -1, -1]))
    xml = tmp_path / "plain.musicxml"
    score(staff()).write("musicxml", fp=str(xml))
    mxl = tmp_path / "packed" / "plain.mxl"
    mxl.parent.mkdir()
    score(staff()).write("mxl", fp=str(mxl))
    for path in (xml, mxl):
        assert_same(load_song(path), want)


def test_errors_name_file_and_measure(tmp_path):
    low = tmp_path / "low.musicxml"  # measure 2 ends on C2 (sounding), below the low E string
    score(staff(last="C2")).write("musicxml", fp=str(low))
    with pytest.raises(SongError, match=r"low\.musicxml:measure 2: .*C2 \(36\) is outside the guitar's range"):
        load_song(low)

    both = dict(TAB_FRETS, C5=(3, 5))  # C4 on string 3 with G3 of the same chord
    xml, _ = write_tab_files(tmp_path, both)
    with pytest.raises(SongError, match=r"tab\.musicxml:measure 1: two notes on string 3 at once"):
        load_song(xml)

    wrong = dict(TAB_FRETS, A4=(3, 3))  # fret 3 on the G string sounds A#3, not A3
    xml, _ = write_tab_files(tmp_path, wrong)
    with pytest.raises(SongError, match=r"measure 1: string 3, fret 3 sounds A#3 .*standard tuning"):
        load_song(xml)

    broken = tmp_path / "broken.musicxml"
    broken.write_text("<score-partwise>\n<part id='P1'>\n<measure>\n</part>")
    with pytest.raises(SongError, match=r"broken\.musicxml:line 4, column \d+: cannot read as MusicXML"):
        load_song(broken)
