"""Test-wide settings: a persistent XLA compilation cache, so that a computation compiled by one test (or an earlier
run of the suite) is not compiled again by the next one; the suite is dominated by compiling the scanned envs.
Rendering tests take the `offscreen_gl` fixture.

The suite runs on 2 processes (`make test`: `-n 2 --dist loadfile`), a file's tests in one process, the files in the
order of `FIRST` (`pytest_collection_modifyitems`)."""
import os
from pathlib import Path

import jax
import pytest

from dexguitar.learn.run import FAST_COMPILE, xla_flags

# LLVM at -O0 for the tests' programs (and for the processes they start, which inherit the environment): XLA's own
# graph optimizations all still run, only the machine code is less tuned; it compiles the training programs ~40%
# faster on a CPU, and the tiny test workloads barely notice the slower code. XLA's older loop emitters instead of its
# fusion emitters take about as much again (tests/test_envs.py, two at once on 2 cores: 138 -> 73 s). Set before
# JAX starts its backend.
# And the flag the commands themselves add (`learn/run.py`, `FAST_COMPILE`): JAX's persistent-cache keys hash XLA_FLAGS
# as it is at each compile, so a test calling `cli.main` would otherwise change the keys of every later compile in its
# process, and miss the programs that earlier tests cached (on a 2-core machine: 19.5 min, 17.6 min with the flag here).
# One LLVM module per program rather than several compiled by parallel threads: each of the 2 test processes keeps one
# core busy already, and the split itself costs (a duet step: 8.4 -> 7.4 s).
# Five of XLA's optional rewrites left out: three loop rewrites (hoisting, sinking, simplifying), the tree reduction
# rewriter and the reshape mover. They change how a program is computed, not what it computes (sums of long rows add
# in another order). The algebraic simplifier stays: XLA's CPU code emitter relies on it to remove the negative
# paddings that the gradient of a slice makes.
SKIPPED_PASSES = ("while-loop-invariant-code-motion", "simplify-while-loops", "while-loop-constant-sinking",
                  "tree_reduction_rewriter", "reshape-mover")
os.environ["XLA_FLAGS"] = xla_flags(os.environ.get("XLA_FLAGS", ""), ("--xla_backend_optimization_level=0",
                                                                      "--xla_cpu_use_fusion_emitters=false",
                                                                      "--xla_cpu_parallel_codegen_split_count=1",
                                                                      "--xla_disable_hlo_passes=" + ",".join(
                                                                          SKIPPED_PASSES),
                                                                      FAST_COMPILE))

# an empty DEXGUITAR_TEST_CACHE is unset (not the working directory, which would fill with cache files)
CACHE = Path(os.environ.get("DEXGUITAR_TEST_CACHE") or Path(__file__).resolve().parent.parent / ".cache" / "xla")
jax.config.update("jax_compilation_cache_dir", str(CACHE))
jax.config.update("jax_persistent_cache_min_compile_time_secs", 2.0)
# the commands that tests call (`cli.main`) set their own cache from DEXGUITAR_CACHE: the same one
os.environ["DEXGUITAR_CACHE"] = str(CACHE)
# the planner's plans of residual left hands (`planner/plans.py`) beside it, not in the user's home
os.environ.setdefault("DEXGUITAR_PLANS", str(CACHE.parent / "plans"))


# one entry per XLA compilation (JAX's own event) or training chunk loaded from its file (`learn.executable`), for
# the compile-once tests
COMPILES = []
jax.monitoring.register_event_duration_secs_listener(
    lambda name, secs, **kw: COMPILES.append(name) if name in ("/jax/core/compile/backend_compile_duration",
                                                                "/dexguitar/chunk/load_duration") else None)

# DEXGUITAR_COMPILE_LOG=DIR: each test process appends, per trace, lowering, compile or chunk load of over 0.3 s, a
# line "test<TAB>event<TAB>function<TAB>seconds" to DIR/<pid>.tsv (docs/tests.md: where the suite's time goes)
RUNNING = ["(collection)"]
if os.environ.get("DEXGUITAR_COMPILE_LOG"):
    _LOG = Path(os.environ["DEXGUITAR_COMPILE_LOG"]) / f"{os.getpid()}.tsv"
    _LOG.parent.mkdir(parents=True, exist_ok=True)

    def _log_compile(name, secs, **kw):
        if name.startswith(("/jax/core/compile/", "/dexguitar/chunk/")) and secs > 0.3:
            with open(_LOG, "a") as f:
                f.write(f"{RUNNING[0]}\t{name.rsplit('/', 1)[1]}\t{kw.get('fun_name')}\t{secs:.2f}\n")
    jax.monitoring.register_event_duration_secs_listener(_log_compile)


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_protocol(item, nextitem):
    RUNNING[0] = item.nodeid
    yield


@pytest.fixture
def compiles():
    """The number of XLA compilations (and training chunks loaded from their files) so far in this process."""
    return lambda: len(COMPILES)


@pytest.fixture
def export_compiles(compiles, monkeypatch):
    """A list that gets the compile count (`compiles`) at each export of a run, the last thing a host call of `train`
    does: the difference of two entries is what the later host call compiled."""
    from dexguitar.learn import checkpoint as C
    counts, save = [], C.Saver.save

    def counting_save(saver, *args, **kwargs):
        done = save(saver, *args, **kwargs)
        if saver.directory.parent.name == "policy":
            counts.append(compiles())
        return done
    monkeypatch.setattr(C.Saver, "save", counting_save)
    return counts


@pytest.fixture(scope="session")
def compiled_chunk():
    """compiled_chunk(trainer, state): one training iteration got as `train` gets it (`learn.run.chunk_build`), so
    that a later `train` of the same program takes it rather than trace and compile it again: in this process from
    memory, in another (a test's subprocess, a notebook) from its file beside the compilation cache.
    -> (chunk, state, data, put): the state and data placed, and `put` to place another (restored) state alike."""
    from dexguitar.learn import run as RUN
    from dexguitar.learn.devices import Placement

    def build(trainer, state):
        where = Placement()
        shardings = where.shardings(state)
        state, data = where.put(state, shardings), where.put(trainer.data, where.replicated(trainer.data))
        chunk, _, _ = RUN.chunk_build(trainer, where, data, lambda msg: None).result()
        return chunk, state, data, lambda tree: where.put(tree, shardings)
    return build


@pytest.fixture(scope="session")
def left_trainer():
    """The tiny left-hand trainer that several test files share (tests/tiny.py): one compiled program for all."""
    import tiny
    return tiny.left_trainer()


@pytest.fixture(scope="session")
def offscreen_gl() -> str:
    """The offscreen OpenGL backend that rendering tests draw with. Without one a rendering test is skipped, except
    under CI (`CI=true`), where it fails: a green CI must mean that the videos render (issue #14)."""
    from dexguitar.motion import glcheck
    try:
        return glcheck.backend()
    except glcheck.NoGL as err:
        if os.environ.get("CI", "").lower() in ("true", "1"):
            pytest.fail(f"CI without an offscreen OpenGL: {err}")
        pytest.skip(str(err))


# ------------------------------------------------------------------------------------------- scheduling (xdist)
# A file's tests run in one process, in order. The training chunks they share are compiled once, by the first file of
# this order that needs one (the left hand's by test_faults.py, the synchronizer's by test_sync.py), and kept in a file
# beside the compilation cache that a later process loads (`compiled_chunk`, `learn.executable`), so the files that
# need them start after those two. xdist gives a process its next file when it has at most 2 tests left: the process
# of test_faults.py, whose tests end before test_sync.py's, usually takes test_devices.py next, which then takes the
# left hand's chunk from memory instead of loading its file (8-13 s). Longest first otherwise; measured with an empty
# cache, 2 processes.
FIRST = ("tests/test_faults.py", "tests/test_sync.py", "tests/test_devices.py", "tests/test_notebooks.py",
         "tests/test_scripted.py", "tests/test_feedforward.py", "tests/test_envs.py", "tests/test_compile_once.py",
         "tests/test_learn.py", "tests/test_world.py", "tests/test_install.py", "tests/test_plan_robustness.py",
         "tests/test_cursor.py", "tests/test_retarget.py", "tests/test_rewards_metrics.py", "tests/test_perform.py",
         "tests/test_detect.py")


def pytest_configure(config):
    # keep the order below: xdist's default puts the files with the most tests first, whatever their length
    if hasattr(config.option, "loadscopereorder"):
        config.option.loadscopereorder = False


def pytest_collection_modifyitems(config, items):
    rank = {name: i for i, name in enumerate(FIRST)}
    order = {id(item): i for i, item in enumerate(items)}      # a stable sort: a file's tests keep their order
    items.sort(key=lambda item: (rank.get(item.nodeid.split("::")[0], len(FIRST)), order[id(item)]))
