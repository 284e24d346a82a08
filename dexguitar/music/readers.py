"""One reader per tab format, chosen by the file suffix."""
from __future__ import annotations

from pathlib import Path

from dexguitar.music.guitarpro import read_guitarpro
from dexguitar.music.midi import read_midi
from dexguitar.music.song import Song, SongError
from dexguitar.music.tab_ascii import read_ascii_tab
from dexguitar.music.tab_json import read_json_tab

READERS = {  # file suffix -> reader
    ".json": read_json_tab,
    ".txt": read_ascii_tab,
    ".tab": read_ascii_tab,
    ".gp3": read_guitarpro,
    ".gp4": read_guitarpro,
    ".gp5": read_guitarpro,
    ".mid": read_midi,
    ".midi": read_midi,
}


def read_tab(path: str | Path, **options) -> Song:
    """Read a tab file of any supported format."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in READERS:
        raise SongError(path, None, f"unknown tab format '{suffix}'; expected one of {', '.join(sorted(READERS))}")
    return READERS[suffix](path, **options)


__all__ = ["READERS", "read_tab"]
