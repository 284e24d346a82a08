"""One reader per tab format, chosen by the file suffix; `read_tab` is the one entry that checks what every format
must keep (a regular file, a track that exists, something to play)."""
from __future__ import annotations

import inspect
from pathlib import Path

from dexguitar.music.guitarpro import read_guitarpro
from dexguitar.music.midi import read_midi
from dexguitar.music.musicxml import read_musicxml
from dexguitar.music.song import Song, SongError, check_file, check_playable
from dexguitar.music.tab_ascii import read_ascii_tab
from dexguitar.music.tab_json import read_json_tab

READERS = {  # file suffix -> reader(path, **options); a reader of files with several tracks takes `track`
    ".json": read_json_tab,
    ".txt": read_ascii_tab,
    ".tab": read_ascii_tab,
    ".gp3": read_guitarpro,
    ".gp4": read_guitarpro,
    ".gp5": read_guitarpro,
    ".mid": read_midi,
    ".midi": read_midi,
    ".musicxml": read_musicxml,
    ".mxl": read_musicxml,
}


def read_tab(path: str | Path, *, track: int | None = None, **options) -> Song:
    """Read a tab file of any supported format. `track` (0-based) picks a track of a multi-track format (None: the
    reader's default, see each reader); a single-track format has only track 0. Special files (FIFO, device, socket,
    directory) are refused before anything opens them, and so is a song whose notes are all rests."""
    path = Path(path)
    check_file(path)
    suffix = path.suffix.lower()
    if suffix not in READERS:
        raise SongError(path, None, f"unknown tab format '{suffix}'; expected one of {', '.join(sorted(READERS))}")
    reader = READERS[suffix]
    if track is not None:
        if "track" in inspect.signature(reader).parameters:
            options["track"] = track
        elif track != 0:
            raise SongError(path, None, f"track {track} does not exist: a {suffix} file holds one track (0)")
    return check_playable(reader(path, **options), path)


__all__ = ["READERS", "read_tab"]
