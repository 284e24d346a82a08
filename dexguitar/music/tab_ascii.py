"""Plain-text ASCII tab reader: the tab guitarists paste from the web -> `Song`.

Syntax (everything is case-insensitive where letters are involved, unless noted)
===============================================================================

Systems
    A *system* is a block of six consecutive *string lines*, top line = string 1 (high E) ... bottom line =
    string 6 (low E); only six-string standard tuning is supported. A string line is an optional label (a note
    name such as ``e``, ``B``, ``E``, ``E2``, upper or lower case; it must name the standard-tuning string of its
    row, so ``e B G D A E`` and ``E B G D A E`` both work and ``E A D G B e`` or ``D A D G B E`` are errors)
    followed by the tab body, which starts with ``|`` or ``-`` and contains no blanks and no words (a line
    with two letters in a row, other than ``xx``, is text such as ``A-men``)::

        e|--0-----|-----3--|        |--0-----|        --0-----
        B|----1---|--------|        |----1---|        ----1---
        ...                         ...               ...

    Six, twelve, ... consecutive string lines are read six by six (systems written back to back); any other
    count is an error naming the first line past the last whole system. A line that is no string line but holds
    only tab characters with frets or ``x`` and dashes or bar lines (``3---|``, ``h|--3--|``, ``|--3 --|``) is
    an error too. Everything else in the file -- titles, chord names, lyrics, blank lines, ``[Verse]`` marks, a
    line of dashes -- is skipped; the systems are concatenated in time as if they were one long line. A string
    line may carry a trailing comment after its final bar line and a blank (``|--0--|  x2``); it is ignored
    (repeats are not expanded).

Rhythm: every column is one grid unit
    Inside a system every character column except bar-line columns (``|``, and ``:`` of ``|:`` / ``:|`` repeat
    marks, which may also be doubled ``||``) is one *grid unit*. The grid unit defaults to 1/16 of a whole
    note per column (so ``4---`` is a quarter note, a 4/4 bar is 16 columns) and the tempo to 120
    quarter-note beats per minute. A note starts at its onset column and lasts until the next onset on any
    string -- in the same or a following system -- and the last note lasts to the end of the last system
    (trailing dashes before the final bar count). Columns where nothing starts simply extend the sounding
    note. All six lines of a system must have the same length and their bar lines must be in the same
    columns (aligned by where each body starts, so labels may differ in width).

Notes
    ``0``..``22``: the fret (``0`` = open string). A two-digit fret occupies two columns; its onset is its
    first column (a leading zero, ``05``, is an error), so two single-digit frets on one string need a
    ``-`` between them (``3-5``, not ``35``). Digits starting in the same column on several lines
    form one note (a chord); a note contains only the strings with an onset in its column -- nothing keeps
    ringing implicitly.
    ``x``: muted string, not played. A column that holds ``x`` marks and nothing else (only ``-``/``~`` on the
    other lines) is a *rest* onset: a muted strum silences the strings. An ``x`` next to frets in a chord
    column just means that string is not played.
    ``~``: vibrato, read as a plain ``-`` (one grid unit, nothing starts).

Effects (the second fret gets the flag; the connector itself is one grid unit of the first note)
    ``5h7`` hammer-on (``Effect.HAMMER``; the second fret must be higher), ``7p5`` pull-off (``Effect.PULL``;
    lower), ``5/7``, ``7\\5`` or ``5s7`` slide (``Effect.SLIDE``; either direction, the frets must differ).
    A connector needs a fret directly on both sides on the same string: ``12h14`` gives two notes, 12 then
    14 with HAMMER.
    ``(5)``: a tie (``Effect.TIE``): the string keeps sounding from the previous note, which must play the
    same fret on that string. The onset of a tie is its ``(`` column.

Rests
    A rest (all strings ``MUTE``) arises only (a) before the first onset of the song, when the first system
    does not start with a note, and (b) at an explicit ``x``-only column (see above).

Header lines (anywhere outside the systems; each at most once)
    ``title: Ode to Joy`` -- the song title (default: the file stem). Needs ``:`` or ``=``.
    ``tempo: 100`` / ``bpm = 100`` / ``Tempo 100`` / ``tempo: 100 bpm`` -- quarter-note beats per minute.
    ``grid: 1/16`` / ``grid = 1/8`` / ``grid 1/12`` / ``grid: 16`` (an integer n means 1/n) -- the duration of
    one column as a fraction of a whole note (``1/12`` = triplet eighths).
    The ``tempo``, ``grid`` and ``title`` options of `read_ascii_tab` override the file.
    A ``tempo``/``bpm``/``grid`` line without ``:`` or ``=`` whose value does not start with a digit is
    ordinary text; with ``:`` or ``=`` a malformed value is an error.

Chord hints for the left hand (paper Fig. 13: the left hand holds the shape, the right hand picks strings)
    Define shapes with header lines in standard chord notation, *low E first*, ``x`` = not in the chord::

        chord Am = x02210
        chord: Bm7 = x 2 4 2 3 2        (blanks or commas between entries allow two-digit frets)

    and put a ``chords:`` line *directly above* a system, each name aligned with the column where its hint
    starts::

        chords: Am          C           -
        e|0-----0-----|0-----0-----|0-----|
        ...

    The first name on the line holds from the start of the system (repeat the held chord if it continues
    from the previous system -- the ``chords:`` keyword itself occupies the first columns); every further
    name starts at the grid column under its first character (a name over a bar line starts at the next
    column). A hint holds until the next name -- across systems too -- and the name ``-`` or ``.`` ends it
    (no hint). Systems without a ``chords:`` line keep the current hint. Every note (rests included) gets
    the hint active at its onset as `Note.chord` (index 0 = string 1 = high E: the reverse of chord
    notation). The reader does not check that the picked frets agree with the hint. A ``chords:`` line that
    is not directly above a system is ordinary text; a name used in one that has no ``chord`` definition
    is an error.

Errors
    Bad input raises `SongError(path, "line L, column C", what was expected)` (1-based text line and column;
    tabs are expanded to 8 columns); nothing half-parsed is returned. A file larger than `song.MAX_FILE_BYTES` is
    refused unread, and the song must keep the limits of `timing` (tempo, shortest note, length; those errors name
    the note by its 0-based index). Parsing takes time linear in the file.
"""
from __future__ import annotations

import bisect
import dataclasses
import re
from fractions import Fraction
from pathlib import Path

from dexguitar.music.song import MUTE, Effect, Note, Song, SongError, read_bytes
from dexguitar.music.timing import check_tempo, validate
from dexguitar.world.guitar import N_FRETS, N_STRINGS

DEFAULT_TEMPO = 120.0                 # quarter-note beats per minute
DEFAULT_GRID = Fraction(1, 16)        # one tab column = a sixteenth note
STANDARD_LABELS = ("e", "b", "g", "d", "a", "e")  # string 1 ... 6

_CONNECTORS = {"h": Effect.HAMMER, "p": Effect.PULL, "/": Effect.SLIDE, "\\": Effect.SLIDE, "s": Effect.SLIDE}
_CONNECTOR_NAMES = {"h": "hammer-on 'h'", "p": "pull-off 'p'", "/": "slide '/'", "\\": "slide '\\'",
                    "s": "slide 's'"}
_BAR_CHARS = "|:"
_SPACER_CHARS = "-~"
_EXPECTED_CHARS = ("frets 0-22, '-', '|', 'x' (mute), h/p (hammer-on/pull-off), '/' '\\' 's' (slide), "
                   "'(n)' (tie) or '~'")

# optional label, then a body starting with '|' or '-' and no blanks; an optional comment after a final '|'. Every
# blank before the body belongs to exactly one group, so a non-matching line fails in linear time.
_STRING_LINE = re.compile(
    r"^(?P<indent>[ ]*)(?:(?P<label>[A-Ga-g][#b]?\d?)[ ]*)?(?P<body>[|\-]\S*?)(?:(?<=\|)[ ]+\S.*)?[ ]*$")
_WORD = re.compile(r"[A-Za-z]{2,}")
# A line that is no string line but holds only tab characters, with a run of dashes or a bar line and a fret or mute
# ("3---|", "h|--3--|", "|--3-- --|"): a string line written wrong, refused rather than skipped as text.
_TAB_CHARS = frozenset("0123456789-|:xX~hpsHPS/\\()")
_LOOSE_LABEL = re.compile(r"^\s*(?P<label>[A-WYZa-wyz][#b]?\d?(?=[\s|\-(\d]))?")
_HEADER = re.compile(r"^\s*(?P<key>title|tempo|bpm|grid|chords|chord)\b\s*(?P<sep>[:=])?\s*(?P<value>.*)$",
                     re.IGNORECASE)  # lines are stripped on the right: the value ends with the line
_TEMPO_VALUE = re.compile(r"^(\d+(?:\.\d*)?|\.\d+)\s*(?:bpm)?$", re.IGNORECASE)
_CHORD_DEF = re.compile(r"^(?P<name>[^\s=]+)\s*=\s*(?P<shape>\S.*)$")
_TIE = re.compile(r"\((\d{1,2})\)")


@dataclasses.dataclass
class _StringLine:
    lineno: int            # 1-based
    label: str | None
    label_col: int         # 0-based text column of the label (of the body when there is no label)
    start: int             # 0-based text column of the body's first character
    body: str


@dataclasses.dataclass
class _Onset:
    fret: int
    effect: Effect
    lineno: int
    col: int               # 1-based text column


@dataclasses.dataclass
class _System:
    lines: list[_StringLine]
    width: int                               # grid columns
    onsets: list[dict[int, _Onset]]          # per grid column: string index -> onset
    rest_columns: set[int]
    grid_of_body: list[int]                  # body index -> grid column (a bar maps to the next column)


def read_ascii_tab(source: str | Path, *, tempo: float | None = None, grid: str | Fraction | int | None = None,
                   title: str | None = None) -> Song:
    """Read an ASCII tab file (see the module docstring for the syntax). Options override the file's headers."""
    path = Path(source)
    try:
        text = read_bytes(path).decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        raise SongError(path, f"byte {exc.start}", f"cannot read the file as UTF-8 text ({exc.reason})") from None
    return parse_ascii_tab(text, path=path, tempo=tempo, grid=grid, title=title)


def parse_ascii_tab(text: str, *, path: str | Path | None = None, tempo: float | None = None,
                    grid: str | Fraction | int | None = None, title: str | None = None) -> Song:
    """Parse ASCII tab text; `path` only names the source in error messages and gives the default title."""
    return _Parser(text, path).parse(tempo=tempo, grid=grid, title=title)


class _Parser:
    def __init__(self, text: str, path: str | Path | None):
        self.path = path
        self.lines = [line.expandtabs(8).rstrip() for line in text.lstrip("\ufeff").splitlines()]

    def error(self, lineno: int | None, col: int | None, message: str) -> SongError:
        where = None
        if lineno is not None:
            where = f"line {lineno}" + (f", column {col}" if col is not None else "")
        return SongError(self.path, where, message)

    # ---------------------------------------------------------------- top level

    def parse(self, *, tempo, grid, title) -> Song:
        systems, system_at = self._find_systems()
        headers, chord_defs, chord_lines = self._read_text_lines(system_at)
        if not systems:
            raise self.error(None, None, "no tab systems found: expected blocks of six string lines such as "
                                         "'e|--0--|' ... 'E|--3--|'")
        parsed = [self._parse_system(lines) for lines in systems]
        hints = self._place_hints(parsed, chord_lines, chord_defs)

        song_tempo = self._tempo_option(tempo) if tempo is not None else headers.get("tempo", DEFAULT_TEMPO)
        song_grid = self._grid_option(grid) if grid is not None else headers.get("grid", DEFAULT_GRID)
        if title is not None:
            song_title = str(title)
        elif "title" in headers:
            song_title = headers["title"]
        else:
            song_title = Path(self.path).stem if self.path is not None else ""
        notes = self._build_notes(parsed, hints, song_grid)
        return validate(Song(tempo=float(song_tempo), notes=tuple(notes), title=song_title), self.path)

    # ---------------------------------------------------------------- pass 1: systems

    def _string_line(self, lineno: int, line: str) -> _StringLine | None:
        m = _STRING_LINE.match(line)
        if m is None:
            return None
        body = m.group("body")
        if any(set(w.lower()) != {"x"} for w in _WORD.findall(body)):
            return None  # words in it: text such as "A-men" or "-Intro-"
        if line[m.end("body"):].strip() and not re.search(r"[-\d]", body):
            return None  # "| C | G |": a chord chart, not a string line
        label_col = m.start("label") if m.group("label") is not None else m.start("body")
        return _StringLine(lineno, m.group("label"), label_col, m.start("body"), body)

    def _find_systems(self):
        systems: list[list[_StringLine]] = []
        system_at: dict[int, int] = {}   # 0-based line index of a system's first line -> system number
        run: list[_StringLine] = []

        def close_run():
            def decoration(s: _StringLine) -> bool:
                return s.label is None and set(s.body) == {"-"}

            while run and len(run) % N_STRINGS and decoration(run[0]):
                del run[0]    # a separator line of dashes right above a system
            while run and len(run) % N_STRINGS and decoration(run[-1]):
                del run[-1]   # ... or right below it
            if not run:
                return
            if len(run) % N_STRINGS:
                first = run[0]
                if len(run) > N_STRINGS:       # blame the first line past the last whole system
                    extra = run[len(run) // N_STRINGS * N_STRINGS]
                    raise self.error(extra.lineno, extra.start + 1,
                                     f"one string line too many (or one missing): lines {first.lineno}-"
                                     f"{run[-1].lineno} are {len(run)} consecutive string lines, and a system has "
                                     f"{N_STRINGS} (string 1 = high E on top; separate systems by a blank line)")
                raise self.error(first.lineno, first.start + 1,
                                 f"a system needs {N_STRINGS} string lines (string 1 = high E on top), found "
                                 f"{len(run)} consecutive string line(s) on lines {first.lineno}-{run[-1].lineno}")
            else:
                for k in range(0, len(run), N_STRINGS):
                    system_at[run[k].lineno - 1] = len(systems)
                    systems.append(run[k:k + N_STRINGS])
            run.clear()

        for index, line in enumerate(self.lines):
            s = self._string_line(index + 1, line)
            if s is None:
                self._check_not_tab(index + 1, line)
                close_run()
            else:
                run.append(s)
        close_run()
        return systems, system_at

    def _check_not_tab(self, lineno: int, line: str) -> None:
        """Refuse a line that is no string line but looks like one (see `_TAB_CHARS`)."""
        label = _LOOSE_LABEL.match(line)
        rest = line[label.end():]
        chars = set(rest) - {" "}
        if not (chars and chars <= _TAB_CHARS and ("--" in rest or "|" in rest) and chars & set("0123456789xX")):
            return
        col = len(line) - len(line.lstrip()) + 1
        if label.group("label") is not None and not re.fullmatch(r"[A-Ga-g][#b]?\d?", label.group("label")):
            why = f"'{label.group('label')}' is not a string name (e B G D A E)"
        elif re.search(r"\S\s+\S", rest.strip()):
            why = "its body has a blank in it"
        else:
            why = "its body starts with neither '|' nor '-'"
        raise self.error(lineno, col, f"this line looks like a string line of tab but {why}: a string line is an "
                                      "optional label (e B G D A E) and a body that starts with '|' or '-' and has "
                                      "no blanks (a comment may follow its final '|' after a blank)")

    # ---------------------------------------------------------------- pass 2: headers and chord lines

    def _read_text_lines(self, system_at: dict[int, int]):
        in_system = set()
        for first in system_at:
            in_system.update(range(first, first + N_STRINGS))
        headers: dict[str, object] = {}
        first_seen: dict[str, int] = {}
        chord_defs: dict[str, tuple[tuple[int, ...], int]] = {}
        chord_lines: dict[int, tuple[int, str]] = {}  # system number -> (line index, text)

        for index, line in enumerate(self.lines):
            if index in in_system:
                continue
            m = _HEADER.match(line)
            if m is None:
                continue
            lineno = index + 1
            key, sep, value = m.group("key").lower(), m.group("sep"), m.group("value")
            col = m.start("value") + 1
            if key == "chords":
                if sep == ":" and index + 1 in system_at:
                    chord_lines[system_at[index + 1]] = (index, line)
                continue
            if key == "chord":
                if sep is None and "=" not in value:
                    continue  # prose such as "Chord progression ..."
                cm = _CHORD_DEF.match(value)
                if cm is None:
                    raise self.error(lineno, col, "malformed chord definition: expected 'chord NAME = SHAPE', "
                                                  "e.g. 'chord Am = x02210' (low E first, x = not in chord)")
                name = cm.group("name")
                if name in ("-", "."):
                    raise self.error(lineno, col, f"'{name}' cannot be a chord name: it ends a chord hint")
                if name in chord_defs:
                    raise self.error(lineno, col, f"chord '{name}' is defined twice (first on line "
                                                  f"{chord_defs[name][1]})")
                shape = self._chord_shape(cm.group("shape"), lineno, m.start("value") + cm.start("shape") + 1)
                chord_defs[name] = (shape, lineno)
                continue
            if key == "bpm":
                key = "tempo"
            if key in ("tempo", "grid") and sep is None and not value[:1].isdigit():
                continue  # prose such as "Tempo is moderate"
            if key == "title" and sep is None:
                continue
            if key in first_seen:
                raise self.error(lineno, m.start("key") + 1,
                                 f"{key} is given twice (first on line {first_seen[key]})")
            if key == "tempo":
                headers[key] = self._tempo_value(value, lineno, col)
            elif key == "grid":
                headers[key] = self._grid_value(value, lineno, col)
            else:
                if not value:
                    raise self.error(lineno, col, "empty title: expected e.g. 'title: Ode to Joy'")
                headers[key] = value
            first_seen[key] = lineno
        return headers, chord_defs, chord_lines

    def _tempo_value(self, value: str, lineno: int | None, col: int | None) -> float:
        m = _TEMPO_VALUE.match(value.strip())
        if m is None:
            raise self.error(lineno, col, f"malformed tempo '{value}': expected a positive number of quarter-note "
                                          "beats per minute, e.g. 'tempo: 100'")
        try:
            check_tempo(float(m.group(1)))
        except ValueError as e:
            raise self.error(lineno, col, str(e)) from None
        return float(m.group(1))

    def _grid_value(self, value: str, lineno: int | None, col: int | None) -> Fraction:
        v = value.strip()
        try:
            if re.fullmatch(r"\d+", v):
                result = Fraction(1, int(v))
            elif re.fullmatch(r"\d+\s*/\s*\d+|\d*\.\d+|\d+\.\d*", v):
                result = Fraction(v.replace(" ", ""))
            else:
                raise ValueError(v)
        except (ValueError, ZeroDivisionError):
            result = Fraction(0)
        if not result > 0:
            raise self.error(lineno, col, f"malformed grid '{value}': expected the duration of one column as a "
                                          "fraction of a whole note, e.g. 'grid: 1/16' (or 'grid: 16')")
        return result

    def _tempo_option(self, tempo) -> float:
        try:
            value = float(tempo)
        except (TypeError, ValueError):
            raise self.error(None, None, f"tempo option must be a number, got {tempo!r}") from None
        try:
            check_tempo(value)
        except ValueError as e:
            raise self.error(None, None, f"tempo option: {e}") from None
        return value

    def _grid_option(self, grid) -> Fraction:
        if isinstance(grid, bool):
            raise self.error(None, None, f"grid option must be a fraction of a whole note, got {grid!r}")
        if isinstance(grid, int):
            grid = str(grid)
        if isinstance(grid, str):
            try:
                return self._grid_value(grid, None, None)
            except SongError:
                raise self.error(None, None, f"grid option '{grid}' is not a fraction such as '1/16'") from None
        try:
            value = Fraction(grid)
        except (TypeError, ValueError):
            value = Fraction(0)
        if not value > 0:
            raise self.error(None, None, f"grid option must be a positive fraction of a whole note, got {grid!r}")
        return value

    def _chord_shape(self, text: str, lineno: int, col: int) -> tuple[int, ...]:
        text = text.strip()
        entries = re.split(r"[\s,]+", text) if re.search(r"[\s,]", text) else list(text)
        if len(entries) != N_STRINGS:
            raise self.error(lineno, col, f"chord shape '{text}' needs {N_STRINGS} entries, low E first "
                                          "(e.g. x02210, or 'x 2 4 4 3 2' for two-digit frets)")
        shape = []
        for entry in entries:
            if entry.lower() == "x":
                shape.append(MUTE)
            elif entry.isdigit() and int(entry) <= N_FRETS:
                shape.append(int(entry))
            else:
                raise self.error(lineno, col, f"chord shape '{text}': entry '{entry}' is neither 'x' nor a fret "
                                              f"0-{N_FRETS}")
        return tuple(reversed(shape))  # chord notation is low E first; Note.chord is string 1 (high E) first

    # ---------------------------------------------------------------- pass 3: system bodies

    def _parse_system(self, lines: list[_StringLine]) -> _System:
        for i, s in enumerate(lines):
            if s.label is not None:
                letter, rest = s.label[0].lower(), s.label[1:].rstrip("0123456789")
                if letter != STANDARD_LABELS[i] or rest:
                    expected = "e B G D A E".split()[i]
                    raise self.error(s.lineno, s.label_col + 1,
                                     f"string label '{s.label}' on string {i + 1}: only six-string standard "
                                     f"tuning is supported, labelled e B G D A E from the top "
                                     f"(expected '{expected}' here)")
        # bodies of the same length, bar lines in the same columns; blame the line that differs from the others
        lengths = [len(s.body) for s in lines]
        length = max(set(lengths), key=lambda n: (lengths.count(n), n))
        for s in lines:
            if len(s.body) != length:
                raise self.error(s.lineno, s.start + min(len(s.body), length) + 1,
                                 f"this string line is {len(s.body)} columns long but the other lines of its system "
                                 f"are {length}: all six lines of a system must have the same length with bar "
                                 "lines in the same columns")
        for p in range(length):
            bars = [s.body[p] in _BAR_CHARS for s in lines]
            if any(bars) and not all(bars):
                odd = bars.count(True) * 2 <= len(bars)   # the minority is the odd one out
                culprit = next(s for s, b in zip(lines, bars) if b == odd)
                other = next(s for s, b in zip(lines, bars) if b != odd)
                what = ("a bar line here that the other lines do not have" if odd else
                        f"no bar line here but line {other.lineno} has one")
                raise self.error(culprit.lineno, culprit.start + p + 1,
                                 f"misaligned bar line: this string line has {what} (bar lines must be in the "
                                 "same columns on all six lines)")
        grid_of_body, g = [], 0
        for p in range(length):
            grid_of_body.append(g)
            if lines[0].body[p] not in _BAR_CHARS:
                g += 1
        width = g
        onsets: list[dict[int, _Onset]] = [dict() for _ in range(width)]
        column_chars: list[list[str]] = [[] for _ in range(width)]
        for i, s in enumerate(lines):
            self._tokenize(i, s, onsets, column_chars)
        rest_columns = {g for g, chars in enumerate(column_chars)
                        if any(c in "xX" for c in chars) and all(c in "xX" + _SPACER_CHARS for c in chars)}
        return _System(lines, width, onsets, rest_columns, grid_of_body)

    def _tokenize(self, string: int, s: _StringLine, onsets, column_chars) -> None:
        body, n = s.body, len(s.body)
        g = 0
        i = 0
        last_fret: int | None = None    # fret of the token that ends right before position i (for connectors)
        pending: tuple[str, int] | None = None  # connector waiting for its second fret: (char, position)

        def col(p: int) -> int:
            return s.start + p + 1

        def fail(p: int, message: str):
            raise self.error(s.lineno, col(p), message)

        def check_fret(value: int, p: int, text: str):
            if len(text) == 2 and text[0] == "0":
                fail(p, f"fret '{text}': a two-digit fret cannot start with 0")
            if value > N_FRETS:
                fail(p, f"fret {value} is above the {N_FRETS}nd fret (expected a fret 0-{N_FRETS})")

        while i < n:
            c = body[i]
            if pending is not None and not c.isdigit():
                ch, at = pending
                fail(at, f"{_CONNECTOR_NAMES[ch]} needs a fret right after it on the same string")
            if c in _BAR_CHARS:
                last_fret = None
                i += 1
                continue
            if c.isdigit():
                j = i
                while j < n and body[j].isdigit():
                    j += 1
                text = body[i:j]
                if len(text) > 2:
                    fail(i, f"fret number '{text}' has more than two digits (expected a fret 0-{N_FRETS}; separate "
                            "consecutive notes with '-')")
                value = int(text)
                check_fret(value, i, text)
                effect = Effect.NONE
                if pending is not None:
                    ch, at = pending
                    effect = _CONNECTORS[ch]
                    if ch == "h" and not value > last_fret:
                        fail(at, f"hammer-on from fret {last_fret} to fret {value}: a hammer-on goes to a higher fret")
                    if ch == "p" and not value < last_fret:
                        fail(at, f"pull-off from fret {last_fret} to fret {value}: a pull-off goes to a lower fret")
                    if effect == Effect.SLIDE and value == last_fret:
                        fail(at, f"slide from fret {last_fret} to the same fret")
                    pending = None
                onsets[g][string] = _Onset(value, effect, s.lineno, col(i))
                for k in range(i, j):
                    column_chars[g].append(body[k])
                    g += 1
                last_fret = value
                i = j
                continue
            if c == "(":
                m = _TIE.match(body, i)
                if m is None:
                    fail(i, "expected a tied fret such as '(5)' after '('")
                value = int(m.group(1))
                check_fret(value, i + 1, m.group(1))
                onsets[g][string] = _Onset(value, Effect.TIE, s.lineno, col(i))
                for k in range(i, m.end()):
                    column_chars[g].append(body[k])
                    g += 1
                last_fret = value
                i = m.end()
                continue
            lower = c.lower()
            if lower in _CONNECTORS:
                if last_fret is None or i == 0 or not (body[i - 1].isdigit() or body[i - 1] == ")"):
                    fail(i, f"{_CONNECTOR_NAMES[lower]} needs a fret right before it on the same string")
                if i + 1 >= n:
                    fail(i, f"{_CONNECTOR_NAMES[lower]} needs a fret right after it on the same string")
                pending = (lower, i)
                column_chars[g].append(c)
                g += 1
                i += 1
                continue
            if c in _SPACER_CHARS or lower == "x":
                column_chars[g].append(c)
                last_fret = None
                g += 1
                i += 1
                continue
            fail(i, f"unknown character {c!r} in a string line; expected {_EXPECTED_CHARS}")
        if pending is not None:
            ch, at = pending
            fail(at, f"{_CONNECTOR_NAMES[ch]} needs a fret right after it on the same string")

    # ---------------------------------------------------------------- chord hints

    def _place_hints(self, systems: list[_System], chord_lines, chord_defs):
        """-> sorted list of (global grid column, shape or None)."""
        offsets, total = [], 0
        for sys in systems:
            offsets.append(total)
            total += sys.width
        hints: list[tuple[int, tuple[int, ...] | None]] = []
        for number in sorted(chord_lines):
            index, line = chord_lines[number]
            lineno = index + 1
            sys = systems[number]
            top = sys.lines[0]
            keyword = re.match(r"\s*chords\s*:", line, re.IGNORECASE)
            names = list(re.finditer(r"\S+", line[keyword.end():]))
            placed: dict[int, str] = {}
            for k, m in enumerate(names):
                name, text_col = m.group(), keyword.end() + m.start()
                if k == 0:
                    g = 0
                else:
                    p = text_col - top.start
                    if p >= len(top.body):
                        raise self.error(lineno, text_col + 1, f"chord name '{name}' lies beyond the end of the "
                                                               "system below it")
                    p = max(p, 0)
                    while p < len(top.body) and top.body[p] in _BAR_CHARS:
                        p += 1
                    if p >= len(top.body):
                        raise self.error(lineno, text_col + 1, f"chord name '{name}' lies beyond the last column "
                                                               "of the system below it")
                    g = sys.grid_of_body[p]
                if g in placed:
                    raise self.error(lineno, text_col + 1, f"chord names '{placed[g]}' and '{name}' start at the "
                                                           "same column of the system")
                placed[g] = name
                if name in ("-", "."):
                    shape = None
                elif name in chord_defs:
                    shape = chord_defs[name][0]
                else:
                    raise self.error(lineno, text_col + 1, f"chord '{name}' is not defined: add a header line "
                                                           f"such as 'chord {name} = x02210' (low E first)")
                hints.append((offsets[number] + g, shape))
        hints.sort(key=lambda h: h[0])
        return hints

    # ---------------------------------------------------------------- notes

    def _build_notes(self, systems: list[_System], hints, grid: Fraction) -> list[Note]:
        starts: list[tuple[int, dict[int, _Onset] | None]] = []  # (global column, onsets or None for a rest)
        offset = 0
        for sys in systems:
            for g in range(sys.width):
                if sys.onsets[g]:
                    starts.append((offset + g, sys.onsets[g]))
                elif g in sys.rest_columns:
                    starts.append((offset + g, None))
            offset += sys.width
        total = offset
        if not any(o is not None for _, o in starts):
            first = systems[0].lines[0]
            raise self.error(first.lineno, first.start + 1, "the tab has no notes: expected frets on the string "
                                                            "lines")
        if starts[0][0] > 0:
            starts.insert(0, (0, None))

        hint_columns = [hg for hg, _ in hints]

        def hint_at(g: int):
            k = bisect.bisect_right(hint_columns, g)
            return hints[k - 1][1] if k else None

        notes: list[Note] = []
        for k, (g, onsets) in enumerate(starts):
            end = starts[k + 1][0] if k + 1 < len(starts) else total
            frets = [MUTE] * N_STRINGS
            effects = [Effect.NONE] * N_STRINGS
            for string, onset in (onsets or {}).items():
                if onset.effect == Effect.TIE:
                    prev = notes[-1].frets[string] if notes else MUTE
                    if prev != onset.fret:
                        was = "does not play that string" if prev == MUTE else f"plays fret {prev}"
                        raise self.error(onset.lineno, onset.col,
                                         f"tie ({onset.fret}) on string {string + 1}: the previous note {was}; a "
                                         "tie continues the same fret from the note right before it")
                frets[string] = onset.fret
                effects[string] = onset.effect
            notes.append(Note(Fraction(end - g) * grid, tuple(frets), tuple(effects), hint_at(g)))
        return notes


__all__ = ["read_ascii_tab", "parse_ascii_tab", "DEFAULT_TEMPO", "DEFAULT_GRID"]
