"""The `dexguitar` command. The Makefile only calls this.

  dexguitar song list|info|convert          embedded songs; tempo, notes, chords, frames; any tab -> JSON tab
  dexguitar train --hand left --song S      one hand: PPO + imitation (resumable)
  dexguitar sync --song S --left L --right R   synchronize both hands; F1 before and after (resumable)
  dexguitar songs TABS... --out DIR         tabs -> left, right, synchronizer -> one F1 row per song (resumable)
  dexguitar eval --ckpt DIR --song S        F1 by the paper's rules, per song and per chord
  dexguitar play --ckpt SYNC --song S       both hands: MP4 with sound, WAV, per-note report (or --left/--right)
  dexguitar plot RUNS --out PNG             F1 against samples
  dexguitar bench env / check / motion      throughput; every scene steps in MJX; reference motions

Library code raises `errors.UserError` for anything the user can fix; only `main` turns it into one line and an exit
code (2). Anything else is a bug and keeps its traceback.
"""
from __future__ import annotations

import argparse
import contextlib
import dataclasses
import json
import os
import sys
import traceback
from pathlib import Path

import jax

from dexguitar import envs as E
from dexguitar.envs.bench import bench_env, check_scenes, default_songs
from dexguitar.errors import UserError
from dexguitar.learn.executable import in_flight
from dexguitar.learn.memory import check_envs, env_bytes, training_bytes
from dexguitar.learn import policy as PO
from dexguitar.configs import load_config, recorded_config
from dexguitar.learn.run import SAVE_EVERY_S, check_init, check_out, compilation_cache, train, xla_flags
from dexguitar.learn.sync import SyncTrainer
from dexguitar.learn.trainer import Trainer
from dexguitar.motion import load_motion
from dexguitar.motion.cli import add_motion_commands
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import library, load_song, procedural
from dexguitar.music import timeline as TL
from dexguitar.music.tab_json import write_json_tab
from dexguitar.perform import pipeline, plots
from dexguitar.perform import motion_quality as MQ
from dexguitar.perform import play as PL
from dexguitar.perform.evaluate import dumps, evaluate, evaluate_synchronizer
from dexguitar.shipped import policies_dir
from dexguitar.world import physics as P

POLICIES = policies_dir()        # $DEXGUITAR_POLICIES, else models/policies as installed (`shipped`)


def positive(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"must be at least 1, got {value}")
    return value


def positive_float(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise argparse.ArgumentTypeError(f"must be positive, got {text}")
    return value


def seconds(text: str) -> float:
    value = float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more, got {text}")
    return value


def track_index(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"tracks are numbered from 0, got {value}")
    return value


VIDEO_SIZES = ((16, 7680), (16, 4320))    # width, height: 16 px up to 8K UHD


def video_size(text: str) -> tuple[int, int]:
    """WIDTHxHEIGHT within VIDEO_SIZES, both even (H.264 video halves the colour planes)."""
    try:
        width, height = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 1280x720, got {text!r}") from None
    (w0, w1), (h0, h1) = VIDEO_SIZES
    if not (w0 <= width <= w1 and h0 <= height <= h1):
        raise argparse.ArgumentTypeError(f"{width}x{height} is outside {w0}..{w1} x {h0}..{h1}")
    if width % 2 or height % 2:
        raise argparse.ArgumentTypeError(f"{width}x{height}: width and height must be even")
    return width, height


def minutes_or_zero(text: str) -> float:
    value = float(text)
    if not value >= 0:
        raise argparse.ArgumentTypeError(f"must be 0 or more, got {text}")
    return value


# ------------------------------------------------------------------------------------------------------- songs

def song_summary(song) -> dict:
    tl = TL.from_song(song)
    frets = song.frets_used
    return {"title": song.title, "tempo": song.tempo, "effective_tempo": round(float(tl.tempo), 3),
            "notes": song.n_notes, "chords": song.n_chords, "rests": len(song.notes) - song.n_notes,
            "seconds": round(song.seconds, 3), "frames": int(tl.n_frames), "frets": list(frets) if frets else None}


def _song_info(args) -> int:
    track = getattr(args, "track", None)
    rows = [{"file": str(source), **song_summary(load_song(source, track=track))} for source in args.files]
    if args.json:
        print(json.dumps(rows[0] if len(rows) == 1 else rows, indent=2))
        return 0
    print(f"{'file':40s} {'tempo':>6s} {'notes':>6s} {'chords':>6s} {'seconds':>8s} {'frames':>7s}  frets")
    for r in rows:
        name = Path(r["file"]).name if Path(r["file"]).exists() else r["file"]
        frets = "-" if r["frets"] is None else f"{r['frets'][0]}-{r['frets'][1]}"
        print(f"{name[-40:]:40s} {r['tempo']:6g} {r['notes']:6d} {r['chords']:6d} {r['seconds']:8.2f} "
              f"{r['frames']:7d}  {frets}")
    return 0


def _song_list(args) -> int:
    return _song_info(argparse.Namespace(files=library.names(), json=getattr(args, "json", False)))


def _song_convert(args) -> int:
    song = load_song(args.source, track=args.track)
    write_json_tab(song, args.out)
    print(f"wrote {args.out}: {song.n_notes} notes, {song.n_chords} chords, {song.seconds:.1f} s")
    return 0


# ------------------------------------------------------------------------------------------------------- checks

def _check(args) -> int:
    """Print the embedded songs, then step every scene (jit + vmap, MJX) and report the speed."""
    print("Embedded songs:")
    _song_list(argparse.Namespace(json=False))
    print(f"\nScenes ({args.envs} envs, JAX on {jax.default_backend()}):")
    ok = True
    for r in check_scenes(args.envs, args.steps, args.mirrored):
        print(f"  {r['scene']:18s} {r['dof']:3d} DoF  compile {r['compile_s']:5.1f} s  "
              f"{r['control_steps_per_s']:9.0f} control steps/s  {'ok' if r['finite'] else 'NOT FINITE'}")
        ok &= r["finite"]
    return 0 if ok else 1


def _bench_env(args) -> int:
    rows = []
    for hand in args.hand:                         # refused before any env is made, not once memory runs out
        check_envs(max(args.envs), 2 * env_bytes(E.make(hand, default_songs(hand), physics="jax")))
    for physics in args.physics:
        for hand in args.hand:
            for n in args.envs:
                for bare in ((False, True) if args.bare else (False,)):
                    r = bench_env(hand, n, args.steps, bare=bare, physics=physics)
                    rows.append(r)
                    label = hand + (" (physics only)" if bare else "")
                    contacts = f"  contacts {r['max_contacts'] / n:4.1f}/env" if r["max_contacts"] >= 0 else ""
                    print(f"{r['physics']:4s} {label:22s} envs {n:6d}  compile {r['compile_s']:6.1f} s  first run "
                          f"{r['first_run_s']:6.1f} s  {r['control_steps_per_s']:11,.0f} control steps/s  "
                          f"{r['physics_steps_per_s']:12,.0f} physics steps/s  solver at {r['solver_iterations']} "
                          f"iterations {100 * r['solver_at_limit']:5.1f} %{contacts}  [{r['device']}]", flush=True)
    if args.json:
        Path(args.json).write_text(json.dumps(rows, indent=2))
    return 0


# ------------------------------------------------------------------------------------------------------- learning

def _material(args, hand: str):
    """The songs named by --song (files, embedded names, folders), or procedural material when none is named."""
    if args.song:
        return library.load_songs(args.song, track=args.track)
    return procedural.material(hand, args.style, 0, args.procedural)


def _physics_set(args) -> list[str]:
    """--set with --physics as the EnvConfig field it sets."""
    return args.set + ([f"env.physics={args.physics}"] if args.physics else [])


def _train(args) -> int:
    with P.stdout_to_stderr():            # stdout: the summary alone, whatever the physics prints while training
        summary = _training(args)
    print(dumps(summary))
    return 0


def _training(args) -> dict:
    cfg, env_cfg = load_config(args.config, _physics_set(args), hand=args.hand, num_envs=args.envs,
                               minibatch=args.minibatch, seed=args.seed, iterations=args.iterations)
    check_out(args.out, args.resume)
    songs = _material(args, cfg.hand)
    motion = load_motion(args.motion or cfg.hand)
    if args.init_from:
        residual = bool(env_cfg and (env_cfg.feedforward or env_cfg.right_feedforward))
        check_init(args.init_from, cfg.hand, residual, cfg.action_scale)            # before building anything
    trainer = Trainer(cfg, [TL.from_song(s) for s in songs], reference_frames(motion), env_cfg, args.devices)
    check_envs(cfg.num_envs, *training_bytes(trainer), devices=args.devices)
    print(f"training the {cfg.hand} hand on {len(songs)} song{'s' * (len(songs) != 1)} with {cfg.num_envs} envs x "
          f"{cfg.horizon} steps ({cfg.batch} samples per iteration) on {jax.devices()[0].device_kind} "
          f"({trainer.env.physics} physics); reference motion {motion.name} "
          f"({motion.qpos.shape[0] / motion.fps:.1f} s); writing {args.out}", file=sys.stderr)
    return train(trainer, args.out, iterations=cfg.iterations, resume=args.resume,
                 meta={"songs": [s.title for s in songs], "motion": motion.name},
                 stop_after_calls=args.stop_after_calls, max_minutes=args.max_minutes, init_from=args.init_from,
                 devices=args.devices, save_every=args.save_every)


def _song_source(source: str) -> str:
    """A --song argument as a resumed run can find it again from any working directory: a file's absolute path, an
    embedded song's name."""
    return str(Path(source).resolve()) if Path(source).exists() else source


def _sync(args) -> int:
    """Synchronize two frozen policies on songs (Sec. 4), then evaluate before and after."""
    out = Path(args.out)
    left, right, song_files = args.left, args.right, args.song
    # --resume continues the run as config.json recorded it: what is not given again is taken from there
    recorded = json.loads((out / "config.json").read_text()) if args.resume and (out / "config.json").exists() else {}
    left, right = left or recorded.get("left"), right or recorded.get("right")
    song_files = song_files or recorded.get("song_files")
    track = args.track if args.track is not None else recorded.get("track")
    if not (left or right) and not args.resume:        # GSync: the general pair
        left, right = _general_pair("sync")
    if not (left and right):
        raise UserError("sync: give --left and --right (exported policies or run directories), or neither for the "
                        "general pair")
    if not song_files:
        raise UserError("sync: give --song (tab files or embedded song names)"
                        + (f"; {out / 'config.json'} records none" if recorded else ""))
    overrides = dict(hand="duet", num_envs=args.envs, minibatch=args.minibatch, seed=args.seed,
                     iterations=args.iterations)
    if recorded and not args.config:
        cfg, env_cfg = recorded_config(recorded, _physics_set(args), **overrides)
    else:
        cfg, env_cfg = load_config(args.config, _physics_set(args), **overrides)
    check_out(out, args.resume)
    songs = [load_song(s, track=track) for s in song_files]
    pair = PO.load_pair(left, right)
    motion = load_motion(args.motion or "left")
    with P.stdout_to_stderr():            # stdout: the results, below
        trainer = SyncTrainer(cfg, [TL.from_song(s) for s in songs], reference_frames(motion), *pair, env_cfg,
                              args.devices)
        check_envs(cfg.num_envs, *training_bytes(trainer), devices=args.devices)
        print(f"synchronizing {left} + {right} on {', '.join(s.title for s in songs)} with {cfg.num_envs} envs x "
              f"{cfg.horizon} steps ({cfg.batch} samples per iteration) on {jax.devices()[0].device_kind} "
              f"({trainer.env.physics} physics); writing {out}", file=sys.stderr)
        summary = train(trainer, out, iterations=cfg.iterations, resume=args.resume,
                        meta={"songs": [s.title for s in songs], "motion": motion.name, "left": str(left),
                              "right": str(right), "song_files": [_song_source(s) for s in song_files],
                              **({"track": track} if track is not None else {})},
                        stop_after_calls=args.stop_after_calls, max_minutes=args.max_minutes, devices=args.devices,
                        save_every=args.save_every)
        print(dumps(summary), file=sys.stderr)
        if args.no_eval:
            return 0
        params, meta = PO.load(out)
        staged = evaluate_synchronizer(params, PO.PolicySpec.from_meta(meta), songs,
                                       E.EnvConfig(physics=trainer.env.physics))
        (out / "eval.json").write_text(dumps({stage: {k: v["summary"] for k, v in r.items()}
                                              for stage, r in staged.items()}, indent=2))
    for stage, results in staged.items():
        _print_results(results, f"[{stage} synchronization] ")
    return 0


def _songs(args) -> int:
    recipe = pipeline.Recipe(**{k: v for k, v in {
        "left_config": args.config_left, "right_config": args.config_right, "sync_config": args.config_sync,
        "left_init": args.left_init, "right_init": args.right_init, "left_minutes": args.left_minutes,
        "right_minutes": args.right_minutes,
        "sync_minutes": args.sync_minutes, "left_target": args.left_target, "right_target": args.right_target,
        "sync_target": args.sync_target, "judge_seconds": args.judge_seconds, "iterations": args.iterations,
        "envs": args.envs, **{f"{stage}_set": tuple(args.set + getattr(args, f"set_{stage}"))
                              for stage in pipeline.STAGES}}.items() if v is not None})
    if args.left_init == "none":
        recipe = dataclasses.replace(recipe, left_init=None)
    rows = pipeline.run_songs(args.tabs, args.out, recipe, per_song=args.per_song)
    print((Path(args.out) / "songs.md").read_text())
    return 0 if rows else 1


# ------------------------------------------------------------------------------------------------------- results

def _print_results(results: dict, label: str = "") -> None:
    for title, res in results.items():
        s = res["summary"]
        hands = [h for h in ("left", "right", "both") if h in s]
        print(f"{label}{title}: " + "  ".join(
            f"{h} F1 undefined (0 notes: nothing to press or pick)" if s[h]["notes"] == 0 else
            f"{h} F1 {s[h]['f1']:.3f} (P {s[h]['precision']:.3f} R {s[h]['recall']:.3f}, {s[h]['notes']} notes)"
            for h in hands))
        for chord, f1 in sorted(s["chords"].items(), key=lambda kv: kv[1]):
            print(f"    chord {chord:>14s}  F1 {f1:.3f}")
        if "motion" in s:
            print("    " + _motion_line(s["motion"]))


def _motion_line(m: dict) -> str:
    return (f"left-hand motion: jerk {m['jerk']:.4g} rad/s^3, energy {m['energy']:.4g} (rad/s)^2, "
            f"human distance {m['human_distance']:.4f} rad")


def _eval(args) -> int:
    if bool(args.ckpt) == bool(args.left or args.right) or (not args.ckpt and not (args.left and args.right)):
        raise UserError("eval: give either --ckpt or both --left and --right (a pair, unsynchronized)")
    if args.ckpt:
        params, meta = PO.load(args.ckpt)
        spec = PO.PolicySpec.from_meta(meta)
    else:
        params, spec = PL.pair(args.left, args.right)
        meta = spec.to_meta()
    songs = library.load_songs(args.song, track=args.track) if args.song else []
    if args.procedural:
        songs += procedural.material(meta["hand"], args.style, args.seed, args.procedural)
    if not songs:
        raise UserError("eval: give --song and/or --procedural N")
    keep = (lambda r: r) if args.notes else (lambda r: {k: v["summary"] for k, v in r.items()})
    env_config = E.EnvConfig(physics=args.physics)
    human = None
    if args.human:       # the human's finger poses first: a bad file fails before the rollout
        if spec.hand == "right":
            raise UserError("eval --human: the motion line is the left hand's; this policy plays the right hand")
        with P.stdout_to_stderr():
            human = MQ.human_poses(args.human)
    record = human is not None
    if spec.kind == "synchronizer" and args.ckpt:   # before and after synchronization
        with P.stdout_to_stderr():        # stdout: the results alone
            staged = evaluate_synchronizer(params, spec, songs, env_config, record=record)
        means = {stage: MQ.add_to_results(r, human) for stage, r in staged.items()} if record else {}
        if args.json:
            print(dumps({stage: _with_mean(keep(r), means.get(stage)) for stage, r in staged.items()}, indent=2))
            return 0
        for stage, results in staged.items():
            _print_results(results, f"[{stage} synchronization] ")
            if stage in means:
                print(f"[{stage} synchronization] mean {_motion_line(means[stage])}")
        return 0
    with P.stdout_to_stderr():
        results = evaluate(params, spec, songs, env_config, record=record)
    mean = MQ.add_to_results(results, human) if record else None
    if args.json:
        print(dumps(_with_mean(keep(results), mean), indent=2))
        return 0
    _print_results(results)
    if mean is not None:
        print(f"mean over {len(results)} song{'s' * (len(results) != 1)}: {_motion_line(mean)}")
    return 0


def _with_mean(results: dict, mean: dict | None) -> dict:
    """`eval --json` output: the songs, and with --human the mean motion line as "motion_mean"."""
    return results if mean is None else {**results, "motion_mean": mean}


# The general pair: both hands on their IK planners (zero residuals). `sync` takes `right_mixed`, a trained
# right hand, instead: a synchronizer shifts a policy's latent, and a zero residual's output does not depend on it.
GENERAL = {"left": POLICIES / "left_general", "right": POLICIES / "right_general"}
SYNC_RIGHT = POLICIES / "right_mixed"


def _general_pair(command: str) -> tuple[str, str]:
    if not (GENERAL["left"] / "policy.json").exists():
        raise UserError(f"{command}: no general left hand at {GENERAL['left']} (train one with "
                        "`make train-left-general`); give --left and --right")
    return str(GENERAL["left"]), str(SYNC_RIGHT if command == "sync" else GENERAL["right"])


def gsync_for(song: str) -> Path | None:
    """The shipped GSync synchronizer of a song (`models/policies/gsync_<file stem or name>`: the general pair
    synchronized on it), if there is one."""
    ckpt = POLICIES / f"gsync_{Path(song).stem}"
    return ckpt if (ckpt / "policy.json").exists() else None


def _play(args) -> int:
    if not (args.ckpt or args.left or args.right):          # any tab: the general pair, synchronized where shipped
        args.ckpt = gsync_for(args.song)
        if args.ckpt is None:
            args.left, args.right = _general_pair("play")
    if bool(args.ckpt) == bool(args.left or args.right) or (not args.ckpt and not (args.left and args.right)):
        raise UserError("play: give either --ckpt SYNC or both --left and --right")
    if args.ckpt:
        params, meta = PO.load(args.ckpt)
        if meta.get("kind") != "synchronizer":
            raise UserError(f"--ckpt {args.ckpt}: a {meta.get('hand')} hand policy, not a synchronizer (use "
                            f"--left/--right)")
        spec = PO.PolicySpec.from_meta(meta)
        params = PO.unsynchronized(params) if args.unsynchronized else params
    else:
        params, spec = PL.pair(args.left, args.right)
    width, height = args.size
    song = args.song if args.track is None else load_song(args.song, track=args.track)
    with P.stdout_to_stderr() if args.json else contextlib.nullcontext():     # stdout: the report alone
        report = PL.perform(song, params, spec, args.out, seconds=args.seconds, video=not args.frames_only,
                            video_fps=args.fps, width=width, height=height, camera=args.camera,
                            captions=args.caption, quiet=args.json, motion=args.motion,
                            env_config=E.EnvConfig(physics=args.physics).evaluation())
    if args.json:
        print(dumps(report, indent=1))
    return 0


def _plot(args) -> int:
    if args.chords:
        print("wrote", plots.plot_chord_histogram(plots.chords_from_eval(args.runs), args.out))
    else:
        print("wrote", plots.plot_f1(args.runs, args.out, args.labels))
    return 0


# ------------------------------------------------------------------------------------------------------- parser

def _add_run_args(p: argparse.ArgumentParser, out_help: str) -> None:
    """The options every resumable training run has (`train`, `sync`)."""
    p.add_argument("--config", help=f"{CONFIG_HELP} (sync --resume without it: the run's own, from its config.json)")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help=SET_HELP)
    p.add_argument("--out", required=True, help=out_help)
    p.add_argument("--resume", action="store_true", help="continue the run in --out from its last checkpoint")
    p.add_argument("--envs", type=positive, help="override CONFIG.num_envs")
    p.add_argument("--minibatch", type=positive, help="override CONFIG.minibatch (samples per gradient step, all "
                                                      "devices together: scale it with --envs to keep the steps)")
    p.add_argument("--iterations", type=positive, help="override CONFIG.iterations (total, counting resumed ones)")
    p.add_argument("--seed", type=int)
    p.add_argument("--max-minutes", type=positive_float, help="stop (with a checkpoint) after this much wall time")
    p.add_argument("--save-every", type=seconds, default=SAVE_EVERY_S, metavar="SECONDS",
                   help="write the checkpoints at most this often (default: %(default)s; 0: after every chunk of "
                        "iterations), and when the run stops (at its end, --max-minutes, a first Ctrl-C or SIGTERM)")
    p.add_argument("--stop-after-calls", type=positive, help=argparse.SUPPRESS)
    p.add_argument("--devices", type=positive, help="devices that share the envs (default: every device, of every "
                                                    "host with --distributed)")
    p.add_argument("--distributed", action="store_true",
                   help="one process per host, joined by jax.distributed (found from SLURM or Open MPI, or from "
                        "--coordinator/--num-processes/--process-id)")
    p.add_argument("--coordinator", help="host:port of process 0 (with --distributed)")
    p.add_argument("--num-processes", type=positive)
    p.add_argument("--process-id", type=int)
    p.add_argument("--physics", choices=E.PHYSICS, help="MJX's implementation, as --set env.physics=... (default: "
                                                        "the config's, auto: Warp on a GPU where installed)")


CONFIG_HELP = ("a config: the name of one in dexguitar/configs/ (e.g. left_gpu, sync_hold, cpu_smoke) or a .py file "
               "defining CONFIG (a TrainConfig) and optionally ENV (an EnvConfig)")
SET_HELP = ("override a field of the config's TrainConfig (e.g. num_envs=1024), or of its EnvConfig as env.KEY (e.g. "
            "env.hold_reward=0.5); repeatable; recorded in config.json with the config, so --resume checks it")

TRACK_HELP = ("which track of a multi-track tab to read, from 0 (JSON, Guitar Pro, MIDI, MusicXML; an ASCII tab "
              "holds track 0 alone). Without it a JSON tab of several different tracks is refused, naming them; "
              "Guitar Pro takes the first 6-string guitar track in standard tuning, MIDI merges all tracks and "
              "MusicXML takes the first tab staff")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="dexguitar", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)

    song = sub.add_parser("song", help="read, inspect and convert tabs").add_subparsers(dest="song_command",
                                                                                       required=True)
    p = song.add_parser("info", help="tempo, notes, chords, duration, frets of tab files or embedded songs")
    p.add_argument("files", nargs="+", help="tab files (.json .txt .tab .gp3/4/5 .mid) or embedded song names")
    p.add_argument("--track", type=track_index, help=TRACK_HELP)
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_song_info)
    p = song.add_parser("list", help="the embedded songs")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_song_list)
    p = song.add_parser("convert", help="convert any tab to the authors' JSON tab format")
    p.add_argument("source")
    p.add_argument("out", help="the .json file to write")
    p.add_argument("--track", type=track_index, help=TRACK_HELP)
    p.set_defaults(func=_song_convert)

    bench = sub.add_parser("bench", help="throughput benchmarks").add_subparsers(dest="bench_command",
                                                                               required=True)
    p = bench.add_parser("env", help="control and physics steps per second of an env (compile time apart)")
    p.add_argument("--hand", nargs="+", default=["left"], choices=["left", "right", "duet"])
    p.add_argument("--envs", nargs="+", type=positive, default=[4])
    p.add_argument("--steps", type=positive, default=100, help="control steps per timed rollout")
    p.add_argument("--bare", action="store_true", help="also time the MJX physics alone")
    p.add_argument("--physics", nargs="+", default=["auto"], choices=E.PHYSICS,
                   help="MJX's implementations to time, one after the other (auto: Warp on a GPU where installed)")
    p.add_argument("--json", help="write the results to this file")
    p.set_defaults(func=_bench_env)

    p = sub.add_parser("train", help="train one hand (PPO + imitation); resumable")
    p.add_argument("--hand", choices=["left", "right"], default=None)
    p.add_argument("--song", nargs="+", help="tab files, embedded song names or folders (none: procedural)")
    p.add_argument("--track", type=track_index, help=TRACK_HELP)
    p.add_argument("--procedural", type=positive, help="procedural songs when no --song is given (default: the "
                                                       "style's: 2000 general, 64 others)")
    p.add_argument("--style", choices=["general", "exercises", "steady", "paper", "mixed"],
                   help="procedural material. Left hand: general (the general-purpose left hand's balanced chords, "
                        "lines and jumps across the neck; the default) or exercises. Right hand: steady (our "
                        "steady-rhythm patterns), paper (the authors' random ones: a string set and 5-44 frames "
                        "per note) or mixed (half each; the default)")
    p.add_argument("--motion", help="reference motion (.npz/.json; default: the shipped clip for the hand)")
    _add_run_args(p, "run directory (checkpoints, metrics.jsonl, policy/)")
    p.add_argument("--init-from", help="start the policy (and its normalizer) from an exported policy or run")
    p.set_defaults(func=_train)


    p = sub.add_parser("sync", help="synchronize a frozen left and right policy on songs (Sec. 4); resumable")
    p.add_argument("--song", nargs="+", help="tab files or embedded song names (taken from --out on --resume)")
    p.add_argument("--track", type=track_index, help=TRACK_HELP + " (taken from --out on --resume)")
    p.add_argument("--left", help="exported left-hand policy or run directory (taken from --out on --resume; "
                                  "neither --left nor --right: models/policies/left_general and right_mixed)")
    p.add_argument("--right", help="exported right-hand policy or run directory (taken from --out on --resume)")
    p.add_argument("--motion", help="left-hand reference motion for the discriminators (default: the shipped clip)")
    _add_run_args(p, "run directory (checkpoints, metrics.jsonl, policy/, eval.json)")
    p.add_argument("--no-eval", action="store_true", help="skip the before/after evaluation at the end")
    p.set_defaults(func=_sync)

    p = sub.add_parser("songs", help="tabs -> left, right and synchronizer -> F1 per song (resumable; skips what "
                                     "is done)")
    p.add_argument("tabs", nargs="+", help="tab files (or embedded song names)")
    p.add_argument("--out", required=True, help="directory of the stages and the table (songs.json, songs.md)")
    p.add_argument("--per-song", action="store_true", help="a left hand and a synchronizer per song (default: one "
                                                           "of each for all the songs together)")
    p.add_argument("--left-minutes", type=minutes_or_zero, help="0: hand --left-init on untrained")
    p.add_argument("--right-minutes", type=minutes_or_zero, help="0: hand --right-init on untrained")
    p.add_argument("--sync-minutes", type=positive_float)
    for stage in pipeline.STAGES:
        p.add_argument(f"--{stage}-target", type=positive_float, help=f"end the {stage} stage once its best export "
                       f"plays this F1 on the songs (deterministic, whole songs; default "
                       f"{getattr(pipeline.Recipe, stage + '_target')})")
    p.add_argument("--judge-seconds", type=positive_float, help="training time between two judgements of a stage's "
                   f"export (default {pipeline.Recipe.judge_seconds:g})")
    for stage in pipeline.STAGES:
        p.add_argument(f"--config-{stage}", help=f"the {stage} stage's config (default "
                       f"{getattr(pipeline.Recipe, stage + '_config')}): a name in dexguitar/configs/ or a .py file")
        p.add_argument(f"--set-{stage}", action="append", default=[], metavar="KEY=VALUE",
                       help=f"override a field of the {stage} stage's config, as --set")
    p.add_argument("--set", action="append", default=[], metavar="KEY=VALUE", help="override a field of every "
                   "stage's config: KEY of its TrainConfig, env.KEY of its EnvConfig; repeatable; recorded in each "
                   "stage's config.json, so a resumed stage checks it")
    p.add_argument("--left-init", help="the left-hand policy to start from (default models/policies/left_official15; "
                   "'none' with --config-left left_songs: from scratch; with left_residual: a residual on the IK "
                   "planner)")
    p.add_argument("--right-init", help="the right-hand policy to start from (default models/policies/right_mixed)")
    p.add_argument("--envs", type=positive, help="override every stage's num_envs")
    p.add_argument("--iterations", type=positive, help="cap every stage's iterations")
    p.set_defaults(func=_songs)

    p = sub.add_parser("eval", help="F1 per hand by the paper's rules, per song and per chord")
    p.add_argument("--ckpt", help="a run directory or an exported policy directory")
    p.add_argument("--left", help="with --right: a left and a right policy playing together, unsynchronized")
    p.add_argument("--right")
    p.add_argument("--song", nargs="+")
    p.add_argument("--track", type=track_index, help=TRACK_HELP)
    p.add_argument("--procedural", type=int, default=0, help="also N procedural songs (a held-out seed)")
    p.add_argument("--seed", type=int, default=1000, help="seed of the procedural songs (training uses 0)")
    p.add_argument("--style", choices=["general", "exercises", "steady", "paper", "mixed"],
                   help="procedural material, as for train (default: the hand's)")
    p.add_argument("--json", action="store_true")
    p.add_argument("--notes", action="store_true", help="with --json: include the per-note rows")
    p.add_argument("--human", nargs="+", metavar="CSV_OR_MOTION",
                   help="add the left hand's motion line per song and on average (finger jerk, energy, distance "
                        "to the nearest human pose; docs/motion_quality.md) against these motion-capture CSVs "
                        "(left hand retargeted, cached) or left-hand motion files")
    p.add_argument("--physics", default="auto", choices=E.PHYSICS,
                   help="MJX's implementation (auto: Warp on a GPU where warp-lang is installed, else JAX)")
    p.set_defaults(func=_eval)

    add_motion_commands(sub)

    p = sub.add_parser("play", help="both hands play a song: MP4 with sound (or a PNG strip), WAV and a per-note "
                                    "report")
    p.add_argument("--ckpt", help="a synchronizer (`dexguitar sync` run or its policy/): both hands, synchronized "
                                  "(none of --ckpt/--left/--right: models/policies/gsync_<song> if shipped, else "
                                  "the general pair on their planners, left_general and right_general)")
    p.add_argument("--left", help="left-hand policy (exported policy or run directory), without a synchronizer")
    p.add_argument("--right", help="right-hand policy")
    p.add_argument("--unsynchronized", action="store_true", help="with --ckpt: its frozen policies alone")
    p.add_argument("--song", required=True, help="embedded song name or tab file")
    p.add_argument("--track", type=track_index, help=TRACK_HELP)
    p.add_argument("--out", default="perf",
                   help="a file name prefix, not a folder: --out out/demo writes out/demo.mp4 (or .png), "
                        "out/demo.wav and out/demo-report.json, making out/ if needed (default: perf, in the current "
                        "folder)")
    p.add_argument("--seconds", type=positive_float, help="play only the first seconds")
    p.add_argument("--frames-only", action="store_true", help="a PNG contact sheet instead of the video")
    p.add_argument("--fps", type=positive_float, default=30.0, help="video frame rate (the simulation runs at 60)")
    p.add_argument("--size", type=video_size, default=(1280, 720), metavar="WxH",
                   help="video size, even numbers in 16..7680 x 16..4320 (default 1280x720); the PNG contact sheet "
                        "(--frames-only, or without imageio-ffmpeg) is 12 frames of 480x270 whatever the size")
    p.add_argument("--camera", default="front", choices=("front", "closeup"),
                   help="front: the whole guitar and both hands; closeup: the fretting hand, following it")
    p.add_argument("--caption", action="store_true",
                   help="show the song, its tempo, the running F1 and what the string colours mean")
    p.add_argument("--motion", action="store_true",
                   help="also the played motion: OUT-left.npz and OUT-right.npz (each hand's joint values at 60 Hz, "
                        "the `motion` file format) and OUT.bvh (both hands; metres, y-up: Blender's default BVH "
                        "import places them as in the simulation)")
    p.add_argument("--json", action="store_true", help="print the report as JSON")
    p.add_argument("--physics", default="auto", choices=E.PHYSICS,
                   help="MJX's implementation (auto: Warp on a GPU where warp-lang is installed, else JAX)")
    p.set_defaults(func=_play)

    p = sub.add_parser("plot", help="F1 against samples from runs' metrics.jsonl, or the per-chord F1 histogram "
                                    "(Fig. 5) of evaluations (needs the plot extra)")
    p.add_argument("runs", nargs="+", help="run directories or metrics.jsonl files (with --chords: `dexguitar eval "
                                           "--json` outputs)")
    p.add_argument("--chords", action="store_true", help="the histogram of per-chord F1 (paper Fig. 5)")
    p.add_argument("--out", required=True)
    p.add_argument("--labels", nargs="*")
    p.set_defaults(func=_plot)

    p = sub.add_parser("check", help="print the embedded songs and check that every scene steps in MJX")
    p.add_argument("--envs", type=positive, default=4)
    p.add_argument("--steps", type=positive, default=60, help="control steps per timed rollout")
    p.add_argument("--mirrored", action="store_true", help="also the left-handed player's scenes")
    p.set_defaults(func=_check)
    return parser


def main(argv=None) -> int:
    """The `dexguitar` command (argv None: the process's own arguments; then a failure while a training chunk still
    compiles ends the process at once, `_leave`)."""
    leave = _leave if argv is None else (lambda code: code)
    args = build_parser().parse_args(sys.argv[1:] if argv is None else list(argv))
    if getattr(args, "distributed", False):
        jax.distributed.initialize(args.coordinator, args.num_processes, args.process_id)
    if args.command in ("train", "sync", "songs", "eval", "play"):
        os.environ["XLA_FLAGS"] = xla_flags(os.environ.get("XLA_FLAGS", ""))    # read when the backend starts
        compilation_cache()
    try:
        return args.func(args)
    except UserError as err:
        print(f"error: {printable(str(err))}", file=sys.stderr)
        return leave(2)
    except OSError as err:             # a file or directory that cannot be read or written: the user's to fix
        print(printable(f"error: {err.filename or ''}: {err.strerror or err}".lstrip(": ")), file=sys.stderr)
        return leave(2)
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return leave(130)
    except Exception:
        if argv is not None or not in_flight():
            raise
        traceback.print_exc()
        return leave(1)


def printable(text: str) -> str:
    """`text` on one line with every non-printable character escaped as Python writes it (a NUL byte of a file
    as \\x00, a newline as \\n), so that no file's bytes reach the terminal raw."""
    return "".join(c if c.isprintable() else repr(c)[1:-1] for c in text)


def _leave(code: int) -> int:
    """`code`, or, where a training chunk is still compiling in a thread, exit with it at once: Python would wait
    for that compile at exit (about a minute on a fresh GPU; `learn.executable.in_flight`). The run directory is
    closed by then (`learn.run`'s `finally`)."""
    if in_flight():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


if __name__ == "__main__":
    sys.exit(main())
