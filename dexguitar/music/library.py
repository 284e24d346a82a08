"""Embedded songs: public-domain melodies and exercises written as ASCII tab in `dexguitar/music/songs/*.txt`.

The file stem is the song's name (`library.load("ode_to_joy")`); the syntax is `dexguitar.music.tab_ascii`'s.
Every file has a `title:`, `tempo:` and `grid:` header and a comment saying what it exercises. Together they
cover single notes, open strings, chords (barre chords included), strumming, an arpeggio with left-hand chord
hints, a fast passage (>= 150 BPM), high frets (>= 12) and hammer-on / pull-off / slide / tie effects.
"""
from __future__ import annotations

import functools
from pathlib import Path

from dexguitar.music.readers import READERS, read_tab
from dexguitar.music.song import Song, SongError
from dexguitar.music.tab_ascii import read_ascii_tab

SONGS_DIR = Path(__file__).resolve().with_name("songs")


def names() -> list[str]:
    """Names of the embedded songs, sorted."""
    return sorted(p.stem for p in SONGS_DIR.glob("*.txt"))


def path(name: str) -> Path:
    """The tab file of an embedded song."""
    if name not in names():
        raise SongError(None, None, f"no embedded song named '{name}'; available: {', '.join(names())}")
    return SONGS_DIR / f"{name}.txt"


@functools.lru_cache(maxsize=None)
def _load(name: str) -> Song:
    return read_ascii_tab(path(name))


def load_song(source: str | Path, **options) -> Song:
    """A tab file of any supported format (the reader is chosen by the suffix), or an embedded song by name.
    `options` go to `readers.read_tab` (`track`, or a reader's own)."""
    source = Path(source)
    if not source.exists():
        if str(source) in names():
            return load(str(source), **options)
        raise SongError(source, None, "no such file (and no embedded song of that name)")
    return read_tab(source, **options)


def load_songs(sources, **options) -> list[Song]:
    """The songs of every source, in order, so that one argument list can name a whole collection. A source is a tab
    file, an embedded song name or a folder: all the regular files in it that `READERS` can read, sorted by name.
    `options` (e.g. `track`) apply to every file."""
    songs = []
    for source in sources:
        p = Path(source)
        if p.is_dir():
            files = sorted(f for f in p.iterdir() if f.is_file() and f.suffix.lower() in READERS)
            if not files:
                raise SongError(p, None, f"no tab files ({', '.join(READERS)}) in this folder")
            songs += [load_song(f, **options) for f in files]
        elif p.exists() or str(source) in names():     # a FIFO or device too: `read_tab` says what it is
            songs.append(load_song(p, **options))
        else:
            raise SongError(p, None, "no such file, folder or embedded song")
    return songs


def load(name: str, **options) -> Song:
    """Parse an embedded song; `options` (tempo, grid, title, track) are passed to `readers.read_tab`."""
    if options:
        return read_tab(path(name), **options)
    return _load(name)


__all__ = ["SONGS_DIR", "names", "path", "load", "load_song", "load_songs"]
