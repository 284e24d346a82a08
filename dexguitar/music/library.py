"""Embedded songs: public-domain melodies and exercises written as ASCII tab in `dexguitar/music/songs/*.txt`.

The file stem is the song's name (`library.load("ode_to_joy")`); the syntax is `dexguitar.music.tab_ascii`'s.
Every file has a `title:`, `tempo:` and `grid:` header and a comment saying what it exercises. Together they
cover single notes, open strings, chords (barre chords included), strumming, an arpeggio with left-hand chord
hints, a fast passage (>= 150 BPM), high frets (>= 12) and hammer-on / pull-off / slide / tie effects.
"""
from __future__ import annotations

import functools
from pathlib import Path

from dexguitar.music.song import Song, SongError

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
    from dexguitar.music.tab_ascii import read_ascii_tab

    return read_ascii_tab(path(name))


def load(name: str, **options) -> Song:
    """Parse an embedded song; `options` (tempo, grid, title) are passed to `read_ascii_tab`."""
    if options:
        from dexguitar.music.tab_ascii import read_ascii_tab

        return read_ascii_tab(path(name), **options)
    return _load(name)


__all__ = ["SONGS_DIR", "names", "path", "load"]
