"""`dexguitar motion ...` commands; `add_motion_commands(subparsers)` registers them on the main parser.

  dexguitar motion info MOTION [--json]                 hand, fps, frames, seconds, joint ranges used
  dexguitar motion render MOTION --out FILE [--frames N] [--width W --height H] [--camera hand|front]

MOTION is "left" / "right" (the shipped default clips), one of our .npz / .json motion files, or one of the authors'
JSON clips (converted on the fly).
"""
from __future__ import annotations

import json
import sys
import warnings

import numpy as np


def motion_summary(motion) -> dict:
    from dexguitar.motion.format import joint_names, joint_ranges
    q = np.asarray(motion.qpos, np.float64)
    rng = joint_ranges(motion.hand)
    lo, hi = q.min(0), q.max(0)
    return {
        "name": motion.name, "hand": motion.hand, "fps": motion.fps, "frames": motion.n_frames,
        "seconds": round(motion.seconds, 3),
        "joints": {n: {"min": round(float(a), 4), "max": round(float(b), 4),
                       "used": round(float((b - a) / (r[1] - r[0])), 3)}
                   for n, a, b, r in zip(joint_names(motion.hand), lo, hi, rng)},
    }


def _load(source):
    from dexguitar.motion import load_motion
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        motion = load_motion(source)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    return motion


def _info(args) -> int:
    from dexguitar.motion.format import MotionError
    try:
        motion = _load(args.motion)
    except MotionError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    s = motion_summary(motion)
    if args.json:
        print(json.dumps(s, indent=2))
        return 0
    print(f"{args.motion}: {s['name'] or '-'}\n  hand {s['hand']}, {s['fps']:g} fps, {s['frames']} frames, "
          f"{s['seconds']:.2f} s")
    print(f"  {'joint':12s} {'min':>8s} {'max':>8s}  of range")
    for name, j in s["joints"].items():
        print(f"  {name:12s} {j['min']:8.3f} {j['max']:8.3f}  {100 * j['used']:5.1f}%")
    return 0


def _render(args) -> int:
    from dexguitar.motion.format import MotionError
    from dexguitar.motion.render import render_motion
    try:
        motion = _load(args.motion)
        out = render_motion(motion, args.out, frames=args.frames, width=args.width, height=args.height,
                            camera=args.camera)
    except (MotionError, RuntimeError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(f"wrote {out}")
    return 0


def add_motion_commands(subparsers) -> None:
    """Register `motion info` and `motion render` on an argparse subparsers object."""
    motion = subparsers.add_parser("motion", help="inspect and render reference motions").add_subparsers(
        dest="motion_command", required=True)
    p = motion.add_parser("info", help="hand, fps, frames, seconds and joint ranges used of a motion")
    p.add_argument("motion", help='"left" / "right" (shipped defaults), a .npz / .json motion, or an authors\' clip')
    p.add_argument("--json", action="store_true", help="print JSON")
    p.set_defaults(func=_info)
    p = motion.add_parser("render", help="a PNG strip of frames (or an .mp4 with imageio-ffmpeg)")
    p.add_argument("motion", help='"left" / "right" (shipped defaults), a .npz / .json motion, or an authors\' clip')
    p.add_argument("--out", required=True, help="output .png (strip of frames) or .mp4")
    p.add_argument("--frames", type=int, default=8, help="frames in the strip (default 8)")
    p.add_argument("--width", type=int, default=480, help="width of one frame (default 480)")
    p.add_argument("--height", type=int, default=360, help="height of one frame (default 360)")
    p.add_argument("--camera", default="hand", help='"hand" (looking at the hand, default) or a scene camera')
    p.set_defaults(func=_render)


def main(argv=None) -> int:
    """Stand-alone entry (`python -m dexguitar.motion.cli ...`) until the main CLI wires these commands in."""
    import argparse
    parser = argparse.ArgumentParser(prog="dexguitar")
    add_motion_commands(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
