"""A first compile of the training chunk as one program against its stages as programs of their own, compiled in
threads at once: `left_finetune` on `minuet_in_g`, Warp unless PHYS says otherwise, JAX's persistent cache off.
Prints each program's XLA compile time and HLO instructions, and when all were ready.

    XLA_FLAGS=--xla_gpu_enable_triton_gemm=false python experiments/stage_compile.py one|three|two
"""
import concurrent.futures
import dataclasses
import os
import sys
import time

import jax

from dexguitar.configs import load_config
from dexguitar.learn.devices import Placement
from dexguitar.learn.stages import Stages
from dexguitar.learn.trainer import Trainer
from dexguitar.motion import load_motion
from dexguitar.motion.kinematics import reference_frames
from dexguitar.music import library
from dexguitar.music import timeline as TL

jax.config.update("jax_enable_compilation_cache", False)


def main(mode: str):
    cfg, env_cfg = load_config("left_finetune", ["env.physics=" + os.environ.get("PHYS", "warp")], hand="left")
    cfg = dataclasses.replace(cfg, one_program=mode == "one")
    trainer = Trainer(cfg, [TL.from_song(library.load("minuet_in_g"))], reference_frames(load_motion("left")),
                      env_cfg)
    stages = trainer.make_train_chunk(cfg.iterations_per_call)
    if mode == "two":             # act and judge as one program, learn as another
        where = Placement()
        state, data = where.shardings(trainer.state_shapes), where.replicated(trainer.data)
        act_judge = jax.jit(lambda ts, d: trainer.judge(*trainer.act(ts, d, where), d), donate_argnums=0,
                            in_shardings=(state, data), out_shardings=(state, where.steps, where.whole, where.whole))
        stages = Stages([act_judge, stages.programs[-1]], stages.repeat)
    t0 = time.perf_counter()
    lowered = stages.lower(trainer.state_shapes, trainer.data)
    t1 = time.perf_counter()
    print(f"{mode}: trace and lowering {t1 - t0:.1f} s", flush=True)

    def compile_one(i):
        t = time.perf_counter()
        text = lowered[i].compile().as_text()
        return i, time.perf_counter() - t, sum(1 for line in text.splitlines() if " = " in line)
    with concurrent.futures.ThreadPoolExecutor(len(lowered)) as pool:
        for i, seconds, n in pool.map(compile_one, range(len(lowered))):
            print(f"  program {i}: XLA compile {seconds:.1f} s, {n:,} HLO instructions", flush=True)
    print(f"{mode}: all compiled {time.perf_counter() - t1:.1f} s after the trace, ready "
          f"{time.perf_counter() - t0:.1f} s", flush=True)


if __name__ == "__main__":
    main(sys.argv[1])
