"""`dexguitar motion ...` commands; `add_motion_commands(subparsers)` registers them on the main parser.

  dexguitar motion info MOTION [--json]                 hand, fps, frames, seconds, joint ranges used
  dexguitar motion render MOTION --out FILE [--frames N] [--width W --height H] [--camera hand|front]
  dexguitar motion retarget CSV --out MOTION [--hand left|right|both] [--start N --stop N] [--fps F]
                                [--scale uniform|neck|none] [--report FILE.json] [--free-nails] [--no-calibrate]

MOTION is "left" / "right" (the shipped default clips), one of our .npz / .json motion files, or one of the authors'
JSON clips (converted on the fly).
"""
from __future__ import annotations

import argparse
import json
import sys
import warnings

import numpy as np

from dexguitar.motion import load_motion
from dexguitar.motion.format import MotionError, joint_names, joint_ranges
from dexguitar.motion.render import render_motion
from dexguitar.motion.retarget import IKConfig, Registration, RetargetError, retarget_file


def motion_summary(motion) -> dict:
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
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        motion = load_motion(source)
    for w in caught:
        print(f"warning: {w.message}", file=sys.stderr)
    return motion


def _info(args) -> int:
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
    try:
        motion = _load(args.motion)
        out = render_motion(motion, args.out, frames=args.frames, width=args.width, height=args.height,
                            camera=args.camera)
    except (MotionError, RuntimeError, ValueError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(f"wrote {out}")
    return 0


def _retarget(args) -> int:
    cfg = IKConfig(calibrate=not args.no_calibrate, free_nails=args.free_nails)
    log = lambda msg: print(f"warning: {msg}", file=sys.stderr)   # noqa: E731
    try:
        paths, rep = retarget_file(args.csv, args.out, args.hand, start=args.start, stop=args.stop, fps=args.fps,
                                   reg=Registration(scale=args.scale), cfg=cfg, log=log)
    except (RetargetError, MotionError, OSError) as err:
        print(f"error: {err}", file=sys.stderr)
        return 2
    print(_report_table(rep))
    if args.report:
        with open(args.report, "w") as f:
            json.dump(rep, f, indent=2)
        print(f"wrote {args.report}")
    for side, path in paths.items():
        print(f"wrote {path} ({side} hand)")
    return 0


def _report_table(rep: dict) -> str:
    lines = [f"{rep['file']}: {rep['frames']} frames at {rep['fps']:g} fps; marker fit error in mm (guitar frame)"]
    for side, h in rep["hands"].items():
        lines.append(f"  {side} hand (IK {h['seconds']:.1f} s)   {'mean':>6s} {'p95':>6s} {'frames':>7s}")
        for name, r in h["markers"].items():
            if r["frames"]:
                lines.append(f"    {name:8s} {'':12s} {r['mean']:6.1f} {r['p95']:6.1f} {r['frames']:7d}")
            else:
                lines.append(f"    {name:8s} {'':12s} {'-':>6s} {'-':>6s} {0:7d}")
    return "\n".join(lines)


def add_motion_commands(subparsers) -> None:
    """Register `motion info`, `motion render` and `motion retarget` on an argparse subparsers object."""
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
    p = motion.add_parser("retarget", help="human reference motions from the guitarist motion-capture CSVs "
                                           "(marker positions -> our hands' joints, by IK)")
    p.add_argument("csv", help="a marker CSV of the authors' motion capture (e.g. mocap/Arpeggio.csv)")
    p.add_argument("--out", required=True,
                   help="output motion (.npz or .json); with --hand both, <stem>-left / <stem>-right beside it")
    p.add_argument("--hand", default="both", choices=("left", "right", "both"),
                   help="which hand (default both: every hand the file has markers of)")
    p.add_argument("--start", type=int, default=0, help="first frame (default 0)")
    p.add_argument("--stop", type=int, default=None, help="frame to stop before (default: the end)")
    p.add_argument("--fps", type=float, default=None, help="resample the output (default: the capture's 120 fps)")
    p.add_argument("--scale", default="uniform", choices=("uniform", "neck", "none"),
                   help="25.5-inch capture -> our scale length: uniform about the nut (default), along the neck "
                        "only, or none")
    p.add_argument("--report", help="also write the error statistics as JSON")
    p.add_argument("--free-nails", action="store_true",
                   help="calibrate nail markers along the finger too (lower error; fingertips overshoot)")
    p.add_argument("--no-calibrate", action="store_true", help="nominal marker offsets only")
    p.set_defaults(func=_retarget)


def main(argv=None) -> int:
    """Stand-alone entry (`python -m dexguitar.motion.cli ...`) until the main CLI wires these commands in."""
    parser = argparse.ArgumentParser(prog="dexguitar")
    add_motion_commands(parser.add_subparsers(dest="command", required=True))
    args = parser.parse_args(argv)
    return args.func(args)


if __name__ == "__main__":
    sys.exit(main())
