"""The `dexguitar` command. The Makefile only calls this.

  dexguitar song list                      embedded songs
  dexguitar song info FILE|NAME... [--json] tempo, notes, chords, seconds, frames, frets
  dexguitar song convert IN OUT.json       write the authors' JSON tab format
  dexguitar bench env --hand left --envs N  env throughput (control and physics steps/s)
  dexguitar motion info|render MOTION      reference motions
  dexguitar play --left L --right R | --ckpt SYNC --song S --out P   both hands: MP4, WAV, report
  dexguitar train / eval / plot            one hand: PPO + imitation; F1 by the paper's rules; curves
  dexguitar sync --song S --left L --right R --out DIR   synchronize both hands; F1 before and after
  dexguitar check                          the embedded songs, and every scene steps in MJX
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path


def song_summary(song) -> dict:
    from dexguitar.music import timeline
    tl = timeline.from_song(song)
    frets = song.frets_used
    return {
        "title": song.title,
        "tempo": song.tempo,
        "effective_tempo": round(float(tl.tempo), 3),
        "notes": song.n_notes,
        "chords": song.n_chords,
        "rests": len(song.notes) - song.n_notes,
        "seconds": round(song.seconds, 3),
        "frames": int(tl.n_frames),
        "frets": list(frets) if frets else None,
    }


def _song_info(args) -> int:
    from dexguitar.music import load_song
    rows = []
    for source in args.files:
        song = load_song(source)
        rows.append({"file": str(source), **song_summary(song)})
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
    from dexguitar.music import library
    args.files, args.json = library.names(), getattr(args, "json", False)
    return _song_info(args)


def _song_convert(args) -> int:
    from dexguitar.music import load_song
    from dexguitar.music.tab_json import write_json_tab
    song = load_song(args.source)
    write_json_tab(song, args.out)
    print(f"wrote {args.out}: {song.n_notes} notes, {song.n_chords} chords, {song.seconds:.1f} s")
    return 0


def _check(args) -> int:
    """Print the embedded songs, then step every scene (4 envs, jit + vmap, MJX) and report the speed."""
    import jax
    import jax.numpy as jnp
    import mujoco
    import numpy as np
    from dexguitar import mjx as quiet_mjx
    mjx = quiet_mjx()

    from dexguitar.world import scene as S

    print("Embedded songs:")
    _song_list(argparse.Namespace(json=False))
    print(f"\nScenes ({args.envs} envs, {S.SUBSTEPS} physics steps per control step, JAX on {jax.default_backend()}):")
    for name in S.SCENES:
        for mirror in ((False, True) if args.mirrored else (False,)):
            m = S.build_model(name, mirror=mirror)
            mx = mjx.put_model(m)
            d = mujoco.MjData(m)
            mujoco.mj_resetDataKeyframe(m, d, 0)
            batch = jax.tree.map(lambda x: jnp.stack([x] * args.envs), mjx.put_data(m, d))
            ctrl = jnp.broadcast_to(jnp.asarray(m.key_qpos[0]), (args.envs, m.nu))

            @jax.jit
            def rollout(data):
                def control_step(data, _):
                    data = data.replace(ctrl=ctrl)
                    data = jax.vmap(lambda x: jax.lax.fori_loop(0, S.SUBSTEPS, lambda _, y: mjx.step(mx, y), x))(data)
                    return data, None
                return jax.lax.scan(control_step, data, None, length=args.steps)[0]

            t0 = time.perf_counter()
            out = jax.block_until_ready(rollout(batch))
            compile_s = time.perf_counter() - t0
            t0 = time.perf_counter()
            out = jax.block_until_ready(rollout(out))
            run_s = time.perf_counter() - t0
            ok = bool(np.all(np.isfinite(np.asarray(out.qpos))))
            label = name + (" (mirrored)" if mirror else "")
            print(f"  {label:18s} {m.nq:3d} DoF  compile {compile_s:5.1f} s  "
                  f"{args.envs * args.steps / run_s:9.0f} control steps/s  {'ok' if ok else 'NOT FINITE'}")
            if not ok:
                return 1
    return 0


def _bench_env(args) -> int:
    from dexguitar.envs.bench import bench_env
    rows = []
    for hand in args.hand:
        for n in args.envs:
            for bare in ((False, True) if args.bare else (False,)):
                r = bench_env(hand, n, args.steps, bare=bare)
                rows.append(r)
                label = hand + (" (physics only)" if bare else "")
                print(f"{label:22s} envs {n:6d}  compile {r['compile_s']:6.1f} s  "
                      f"{r['control_steps_per_s']:11,.0f} control steps/s  {r['physics_steps_per_s']:12,.0f} "
                      f"physics steps/s  [{r['device']}]", flush=True)
    if args.json:
        import json
        Path(args.json).write_text(json.dumps(rows, indent=2))
    return 0


def _procedural(hand: str, seed: int, n: int, style: str = "mixed"):
    """Procedural material: the left hand's exercises; the right hand's steady-rhythm patterns (ours), the authors'
    random patterns (a string set and 5-44 frames per note), or both, half each ("mixed")."""
    from dexguitar.music import procedural as PR
    if hand != "right":
        if style == "paper":
            raise SystemExit("--style paper is the right hand's procedural material")
        return PR.left_exercises(seed, n)
    if style == "mixed":
        return PR.right_patterns(seed, n - n // 2) + PR.paper_right_patterns(seed, n // 2)
    return {"paper": PR.paper_right_patterns, "steady": PR.right_patterns}[style](seed, n)


def _songs(sources, hand: str, procedural: int, style: str = "mixed"):
    """Songs from files, embedded names or folders; or procedural material when none are given."""
    from dexguitar.music import load_song
    songs = []
    for source in sources or []:
        path = Path(source)
        if path.is_dir():
            files = sorted(p for p in path.iterdir() if p.suffix.lower() in
                           (".json", ".txt", ".tab", ".gp3", ".gp4", ".gp5", ".mid", ".midi"))
            songs += [load_song(p) for p in files]
        else:
            songs.append(load_song(source))
    if not songs:
        songs = _procedural(hand, 0, procedural, style)
    return songs


def _train(args) -> int:
    import jax

    from dexguitar.learn.run import load_config, train
    from dexguitar.learn.trainer import Trainer
    from dexguitar.motion import load_motion
    from dexguitar.motion.kinematics import reference_frames
    from dexguitar.music import timeline as TL
    cfg, env_cfg = load_config(args.config, hand=args.hand, num_envs=args.envs, seed=args.seed,
                               iterations=args.iterations)
    songs = _songs(args.song, cfg.hand, args.procedural, args.style)
    motion = load_motion(args.motion or cfg.hand)
    trainer = Trainer(cfg, [TL.from_song(s) for s in songs], reference_frames(motion), env_cfg)
    print(f"training the {cfg.hand} hand on {len(songs)} song(s) with {cfg.num_envs} envs x {cfg.horizon} steps "
          f"({cfg.batch} samples per iteration) on {jax.devices()[0].device_kind}; reference motion "
          f"{motion.name} ({motion.qpos.shape[0] / motion.fps:.1f} s); writing {args.out}", file=sys.stderr)
    summary = train(trainer, args.out, iterations=cfg.iterations, resume=args.resume,
                    meta={"songs": [s.title for s in songs], "motion": motion.name},
                    stop_after_calls=args.stop_after_calls, max_minutes=args.max_minutes, init_from=args.init_from)
    print(json.dumps(summary))
    return 0


def _print_results(results: dict, label: str = "") -> None:
    for title, res in results.items():
        s = res["summary"]
        hands = [h for h in ("left", "right", "both") if h in s]
        print(f"{label}{title}: " + "  ".join(
            f"{h} F1 {s[h]['f1']:.3f} (P {s[h]['precision']:.3f} R {s[h]['recall']:.3f}, {s[h]['notes']} notes)"
            for h in hands))
        for chord, f1 in sorted(s["chords"].items(), key=lambda kv: kv[1]):
            print(f"    chord {chord:>14s}  F1 {f1:.3f}")


def sync_eval(directory, songs) -> dict:
    """{"before": results, "after": results}: a synchronizer's two frozen policies alone, then synchronized."""
    from dexguitar.learn.run import policy_from
    from dexguitar.perform.evaluate import evaluate
    return {stage: evaluate("duet", policy_from(directory, synchronized=(stage == "after"))[0], songs)
            for stage in ("before", "after")}


def _eval(args) -> int:
    from dexguitar.learn.run import policy_from
    from dexguitar.music import load_song
    from dexguitar.perform.evaluate import evaluate
    act, meta = policy_from(args.ckpt)
    songs = [load_song(s) for s in args.song or []]
    if args.procedural:
        songs += _procedural(meta["hand"], args.seed, args.procedural, args.style)
    if not songs:
        raise SystemExit("eval: give --song and/or --procedural N")
    keep = (lambda r: r) if args.notes else (lambda r: {k: v["summary"] for k, v in r.items()})
    if meta.get("kind") == "synchronizer":             # before and after synchronization
        staged = sync_eval(args.ckpt, songs)
        if args.json:
            print(json.dumps({stage: keep(r) for stage, r in staged.items()}, indent=2))
            return 0
        for stage, results in staged.items():
            _print_results(results, f"[{stage} synchronization] ")
        return 0
    results = evaluate(meta["hand"], act, songs)
    if args.json:
        print(json.dumps(keep(results), indent=2))
        return 0
    _print_results(results)
    return 0


def _sync(args) -> int:
    """Synchronize two frozen policies on a song (Sec. 4), then evaluate before and after."""
    import jax

    from dexguitar.learn.run import load_config, train
    from dexguitar.learn.sync import SyncTrainer, load_pair
    from dexguitar.motion import load_motion
    from dexguitar.motion.kinematics import reference_frames
    from dexguitar.music import load_song
    from dexguitar.music import timeline as TL
    out = Path(args.out)
    left, right = args.left, args.right
    if args.resume and (out / "config.json").exists() and not (left and right):
        recorded = json.loads((out / "config.json").read_text())
        left, right = left or recorded["left"], right or recorded["right"]
    if not (left and right):
        raise SystemExit("sync: give --left and --right (exported policies or run directories)")
    cfg, env_cfg = load_config(args.config, hand="duet", num_envs=args.envs, seed=args.seed,
                               iterations=args.iterations)
    songs = [load_song(s) for s in args.song]
    pair = load_pair(left, right)
    motion = load_motion(args.motion or "left")
    trainer = SyncTrainer(cfg, [TL.from_song(s) for s in songs], reference_frames(motion), *pair, env_cfg)
    print(f"synchronizing {left} + {right} on {', '.join(s.title for s in songs)} with {cfg.num_envs} envs x "
          f"{cfg.horizon} steps ({cfg.batch} samples per iteration) on {jax.devices()[0].device_kind}; "
          f"writing {out}", file=sys.stderr)
    summary = train(trainer, out, iterations=cfg.iterations, resume=args.resume,
                    meta={"songs": [s.title for s in songs], "motion": motion.name, "left": str(left),
                          "right": str(right)},
                    stop_after_calls=args.stop_after_calls, max_minutes=args.max_minutes)
    print(json.dumps(summary), file=sys.stderr)
    if args.no_eval:
        return 0
    staged = sync_eval(out, songs)
    (out / "eval.json").write_text(json.dumps({stage: {k: v["summary"] for k, v in r.items()}
                                               for stage, r in staged.items()}, indent=2))
    for stage, results in staged.items():
        _print_results(results, f"[{stage} synchronization] ")
    return 0


def _play(args) -> int:
    from dexguitar.perform.play import main as play_main
    return play_main(args.rest)


def _plot(args) -> int:
    from dexguitar.perform.plots import plot_f1
    print("wrote", plot_f1(args.runs, args.out, args.labels))
    return 0


def _add_run_args(p: argparse.ArgumentParser, out_help: str) -> None:
    """The options every resumable training run has (`train`, `sync`)."""
    p.add_argument("--config", help="experiments/*.py defining CONFIG (a TrainConfig) and optionally ENV")
    p.add_argument("--out", required=True, help=out_help)
    p.add_argument("--resume", action="store_true", help="continue the run in --out from its last checkpoint")
    p.add_argument("--envs", type=int, help="override CONFIG.num_envs")
    p.add_argument("--iterations", type=int, help="override CONFIG.iterations (total, counting resumed ones)")
    p.add_argument("--seed", type=int)
    p.add_argument("--max-minutes", type=float, help="stop (with a checkpoint) after this much wall time")
    p.add_argument("--stop-after-calls", type=int, help=argparse.SUPPRESS)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="dexguitar", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = parser.add_subparsers(dest="command", required=True)

    song = sub.add_parser("song", help="read, inspect and convert tabs").add_subparsers(dest="song_command",
                                                                                       required=True)
    p = song.add_parser("info", help="tempo, notes, chords, duration, frets of tab files or embedded songs")
    p.add_argument("files", nargs="+", help="tab files (.json .txt .tab .gp3/4/5 .mid) or embedded song names")
    p.add_argument("--json", action="store_true", help="machine-readable output")
    p.set_defaults(func=_song_info)
    p = song.add_parser("list", help="the embedded songs")
    p.add_argument("--json", action="store_true")
    p.set_defaults(func=_song_list)
    p = song.add_parser("convert", help="convert any tab to the authors' JSON tab format")
    p.add_argument("source")
    p.add_argument("out")
    p.set_defaults(func=_song_convert)

    bench = sub.add_parser("bench", help="throughput benchmarks").add_subparsers(dest="bench_command",
                                                                               required=True)
    p = bench.add_parser("env", help="control and physics steps per second of an env (compile time apart)")
    p.add_argument("--hand", nargs="+", default=["left"], choices=["left", "right", "duet"])
    p.add_argument("--envs", nargs="+", type=int, default=[4])
    p.add_argument("--steps", type=int, default=100, help="control steps per timed rollout")
    p.add_argument("--bare", action="store_true", help="also time the MJX physics alone")
    p.add_argument("--json", help="write the results to this file")
    p.set_defaults(func=_bench_env)

    p = sub.add_parser("train", help="train one hand (PPO + imitation); resumable")
    p.add_argument("--hand", choices=["left", "right"], default=None)
    p.add_argument("--song", nargs="*", help="tab files, embedded song names or folders (none: procedural)")
    p.add_argument("--procedural", type=int, default=64, help="procedural songs when no --song is given")
    p.add_argument("--style", choices=["steady", "paper", "mixed"], default="mixed",
                   help="right-hand procedural material: our steady-rhythm patterns, the authors' random ones "
                        "(a string set and 5-44 frames per note), or half each")
    p.add_argument("--motion", help="reference motion (.npz/.json; default: the shipped clip for the hand)")
    _add_run_args(p, "run directory (checkpoints, metrics.jsonl, policy/)")
    p.add_argument("--init-from", help="start the policy (and its normalizer) from an exported policy or run")
    p.set_defaults(func=_train)

    p = sub.add_parser("eval", help="F1 per hand by the paper's rules, per song and per chord")
    p.add_argument("--ckpt", required=True, help="a run directory or an exported policy directory")
    p.add_argument("--song", nargs="*")
    p.add_argument("--procedural", type=int, default=0, help="also N procedural songs (a held-out seed)")
    p.add_argument("--seed", type=int, default=1000, help="seed of the procedural songs (training uses 0)")
    p.add_argument("--style", choices=["steady", "paper", "mixed"], default="steady",
                   help="right hand: our steady-rhythm patterns, the authors' (a random string set and 5-44 "
                        "frames per note), or half each")
    p.add_argument("--json", action="store_true")
    p.add_argument("--notes", action="store_true", help="with --json: include the per-note rows")
    p.set_defaults(func=_eval)

    p = sub.add_parser("sync", help="synchronize a frozen left and right policy on a song (Sec. 4); resumable")
    p.add_argument("--song", nargs="+", required=True, help="tab files or embedded song names")
    p.add_argument("--left", help="exported left-hand policy or run directory (taken from --out on --resume)")
    p.add_argument("--right", help="exported right-hand policy or run directory (taken from --out on --resume)")
    p.add_argument("--motion", help="left-hand reference motion for the discriminators (default: the shipped clip)")
    _add_run_args(p, "run directory (checkpoints, metrics.jsonl, policy/, eval.json)")
    p.add_argument("--no-eval", action="store_true", help="skip the before/after evaluation at the end")
    p.set_defaults(func=_sync)

    from dexguitar.motion.cli import add_motion_commands
    add_motion_commands(sub)

    p = sub.add_parser("play", help="both hands play a song: MP4 (or PNG strip), WAV and a per-note report",
                       add_help=False)
    p.add_argument("rest", nargs=argparse.REMAINDER, help="--left DIR --right DIR --song S --out PREFIX ...")
    p.set_defaults(func=_play)

    p = sub.add_parser("plot", help="F1 against samples from runs' metrics.jsonl (needs the plot extra)")
    p.add_argument("runs", nargs="+", help="run directories or metrics.jsonl files")
    p.add_argument("--out", required=True)
    p.add_argument("--labels", nargs="*")
    p.set_defaults(func=_plot)

    p = sub.add_parser("check", help="print the embedded songs and check that every scene steps in MJX")
    p.add_argument("--envs", type=int, default=4)
    p.add_argument("--steps", type=int, default=60, help="control steps per timed rollout")
    p.add_argument("--mirrored", action="store_true", help="also the left-handed player's scenes")
    p.set_defaults(func=_check)
    return parser


def main(argv=None) -> int:
    from dexguitar.music.song import SongError
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv[:1] == ["play"]:                 # its own parser (perform.play.main), --help included
        return _play(argparse.Namespace(rest=argv[1:]))
    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except SongError as err:
        print(f"error: {err}", file=sys.stderr)
        return 2


if __name__ == "__main__":
    sys.exit(main())
