"""Reference motions: one hand's joint values over time (`Motion`), their files, the link states the envs observe,
the authors' clip reader, the shipped default clips (recorded from `dexguitar.planner`) and rendering.

    format      Motion, save / load (.npz, .json), resample, validate
    kinematics  link_states, reference_frames, finger_segments, velocities (by `world.kinematics`)
    official    read_official_json (the authors' JSON clips, converted to our joints)
    defaults    default_motion(hand), and `python -m dexguitar.motion.defaults` to regenerate the clips
    render      render_motion (PNG strip, or .mp4 with imageio-ffmpeg)
    cli         `motion render`, `motion info`
"""
from pathlib import Path

from dexguitar.motion import defaults, official
from dexguitar.motion.format import Motion, MotionError, load, resample, save, validate


def load_motion(source) -> Motion:
    """A motion from "left" / "right" (the shipped defaults, unless a file of that name is in the working folder; a
    folder of that name, such as a run's `left/`, is no motion), a .npz / .json of ours, or the authors' JSON clip."""
    if str(source) in defaults.CLIPS and not Path(str(source)).is_file():
        return defaults.default_motion(str(source))
    if official.is_official_json(source):
        return official.read_official_json(source)
    return load(source)


__all__ = ["Motion", "MotionError", "load", "save", "resample", "validate", "load_motion"]
