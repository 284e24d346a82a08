"""The training chunk as a chain of programs, each compiled on its own.

An iteration is three stages (`Trainer.act`, `judge`, `learn`), and the chunk runs `repeat` iterations. XLA compiles
a program on one thread: the left hand's chunk as one program, a `lax.scan` of iterations (`TrainConfig.one_program`),
compiles in 21-23 s on an H200 under Warp; its stages as three programs compiled at once, in threads, are all
compiled 9.8 s after their trace (docs/benchmarks.md, "The training program in three"). The price is three calls per
iteration instead of one per chunk, and the stages' outputs (a rollout's trajectory, the PPO batch) kept in device
memory between them, as one program keeps them too.

The convention: the first program takes (state, data), each later one (what the one before returned, data), and
the last returns (state, metrics); the next iteration starts from that state. The metrics of the iterations are
summed on the host, as one program sums them on the device.
"""
from __future__ import annotations

import warnings

import jax
import numpy as np

from dexguitar.learn.tracing import fresh_trace


class Stages:
    """The chain's jitted programs and how many times it runs per call, before compiling."""

    def __init__(self, programs, repeat: int):
        self.programs, self.repeat = list(programs), repeat

    def lower(self, state, data) -> list:
        """Each program lowered for what the one before returns (shapes and shardings only). The first trace starts
        from JAX's empty caches (`tracing`), so that the programs are the same whatever the process traced before."""
        fresh_trace()
        lowered, x = [], state
        for program in self.programs:
            traced = program.trace(x, data)
            with warnings.catch_warnings():
                # each program is given what the one before returned, to reuse its buffers where it can: the rest
                # (a trajectory's rewards, the keys) it frees, which JAX reports as donations not usable
                warnings.filterwarnings("ignore", "Some donated buffers were not usable")
                lowered.append(traced.lower())
            x = traced.out_info
        return lowered


class Chain:
    """The compiled chain, a function (state, data) -> (state, metrics summed over `repeat` iterations)."""

    def __init__(self, programs, repeat: int):
        self.programs, self.repeat = list(programs), repeat

    def __call__(self, state, data):
        metrics = []
        for _ in range(self.repeat):
            x = state
            for program in self.programs[:-1]:
                x = program(x, data)
            state, m = self.programs[-1](x, data)
            metrics.append(m)
        metrics = jax.device_get(metrics)
        return state, jax.tree.map(lambda *xs: np.sum(np.stack(xs)), *metrics)

    def as_text(self) -> str:
        """The compiled programs' text, one after another."""
        return "".join(program.as_text() for program in self.programs)


__all__ = ["Stages", "Chain"]
