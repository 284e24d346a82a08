"""Music input: tab files of every common format -> `Song` -> per-frame `Timeline`."""
from __future__ import annotations

from pathlib import Path

from dexguitar.music.song import MUTE, OPEN, Effect, Note, Song, SongError, make_note

READERS = {  # file suffix -> (module, function); modules are imported on first use
    ".json": ("dexguitar.music.tab_json", "read_json_tab"),
    ".txt": ("dexguitar.music.tab_ascii", "read_ascii_tab"),
    ".tab": ("dexguitar.music.tab_ascii", "read_ascii_tab"),
    ".gp3": ("dexguitar.music.guitarpro", "read_guitarpro"),
    ".gp4": ("dexguitar.music.guitarpro", "read_guitarpro"),
    ".gp5": ("dexguitar.music.guitarpro", "read_guitarpro"),
    ".mid": ("dexguitar.music.midi", "read_midi"),
    ".midi": ("dexguitar.music.midi", "read_midi"),
}


def load_song(path: str | Path, **options) -> Song:
    """Read any supported tab file; the reader is chosen by the file suffix. Embedded songs load by name."""
    import importlib

    path = Path(path)
    if not path.exists():
        from dexguitar.music import library
        if str(path) in library.names():
            return library.load(str(path))
        raise SongError(path, None, "no such file (and no embedded song of that name)")
    suffix = path.suffix.lower()
    if suffix not in READERS:
        raise SongError(path, None, f"unknown tab format '{suffix}'; expected one of {', '.join(sorted(READERS))}")
    module, name = READERS[suffix]
    return getattr(importlib.import_module(module), name)(path, **options)


__all__ = ["MUTE", "OPEN", "Effect", "Note", "Song", "SongError", "make_note", "load_song", "READERS"]
