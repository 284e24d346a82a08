"""Music input: tab files of every common format -> `Song` -> `Timeline` arrays -> `cursor` windows of notes."""
from dexguitar.music.library import load_song, load_songs
from dexguitar.music.readers import READERS
from dexguitar.music.song import MUTE, OPEN, Effect, Note, Song, SongError, make_note

__all__ = ["MUTE", "OPEN", "Effect", "Note", "Song", "SongError", "make_note", "load_song", "load_songs", "READERS"]
