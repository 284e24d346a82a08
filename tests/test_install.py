"""The package as a wheel installs it: built offline from a copy of the sources with the .venv's setuptools, installed
into a folder of its own, and run from another working directory with that folder first on the path, it lists the
embedded songs and plays the demo pair from the policies it carries (`dexguitar.shipped`), reading nothing of the
source tree (no experiments/, no models/)."""
import json
import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def packages_in_the_tree() -> set[str]:
    return {".".join(p.parent.relative_to(ROOT).parts) for p in (ROOT / "dexguitar").rglob("__init__.py")}


def test_pyproject_lists_every_package():
    """pyproject.toml names the packages (it maps models/ to `dexguitar_models` beside them): a new one must be
    added there, or a wheel would lack it."""
    tomllib = pytest.importorskip("tomllib")            # Python 3.11+
    listed = set(tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["setuptools"]["packages"])
    assert listed == packages_in_the_tree() | {"dexguitar_models"}


def run(argv, cwd, env, timeout=600) -> subprocess.CompletedProcess:
    done = subprocess.run(argv, cwd=cwd, env=env, capture_output=True, text=True, timeout=timeout)
    assert done.returncode == 0, f"{argv}: exit {done.returncode}\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
    return done


def test_the_wheel_runs_songs_and_play_on_its_own(tmp_path, offscreen_gl):
    import setuptools
    if int(setuptools.__version__.split(".")[0]) < 77:
        pytest.fail(f"setuptools {setuptools.__version__} cannot build the wheel (pyproject.toml needs >= 77): "
                    "`make setup` installs it (the dev extra)")
    src, site, work = tmp_path / "src", tmp_path / "site", tmp_path / "work"
    # a copy of what the wheel is made of, so that the build writes nothing into the working tree
    shutil.copytree(ROOT / "dexguitar", src / "dexguitar", ignore=shutil.ignore_patterns("__pycache__"))
    shutil.copytree(ROOT / "models" / "policies", src / "models" / "policies")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy(ROOT / name, src / name)
    pip = [sys.executable, "-m", "pip", "--disable-pip-version-check"]
    run(pip + ["wheel", "--no-deps", "--no-build-isolation", "--no-index", "-w", str(tmp_path / "dist"), str(src)],
        tmp_path, os.environ)
    wheel, = (tmp_path / "dist").glob("dexguitar-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    assert {p.replace(".", "/") + "/__init__.py" for p in packages_in_the_tree()} <= names
    assert "dexguitar/configs/cpu_smoke.py" in names and "dexguitar_models/policies/left_general/policy.json" in names
    run(pip + ["install", "--no-deps", "--no-index", "--target", str(site), str(wheel)], tmp_path, os.environ)

    work.mkdir()
    env = {k: v for k, v in os.environ.items() if k not in ("DEXGUITAR_POLICIES", "PYTHONPATH")}
    env.update(PYTHONPATH=str(site), JAX_PLATFORMS="cpu",
               DEXGUITAR_CACHE=os.environ.get("DEXGUITAR_CACHE", ""))   # the suite's XLA cache (conftest.py)
    where = run([sys.executable, "-c", "import dexguitar, dexguitar.shipped as s; "
                 "print(dexguitar.__file__); print(s.policies_dir())"], work, env).stdout.splitlines()
    assert Path(where[0]).is_relative_to(site) and Path(where[1]) == site / "dexguitar_models" / "policies"
    dexguitar = str(site / "bin" / "dexguitar")             # the console script, on the .venv's Python

    listing = subprocess.Popen([dexguitar, "song", "list"], cwd=work, env=env, stdout=subprocess.PIPE,
                               stderr=subprocess.PIPE, text=True)           # beside the play below (2 cores)
    # the demo pair (`make demo`), synchronized, for its first second: its first chord
    demo = Path(where[1]) / "sync_strum_g_c_d"
    run([dexguitar, "play", "--ckpt", str(demo), "--song", "strum_g_c_d", "--seconds", "1", "--frames-only",
         "--out", "out/demo"], work, env)
    songs, err = listing.communicate(timeout=120)
    assert listing.returncode == 0, err
    assert "strum_g_c_d" in songs and "ode_to_joy" in songs
    report = json.loads((work / "out" / "demo-report.json").read_text())
    assert report["title"] == "Strumming G - C - D" and report["summary"]["both"]["notes"] >= 1
    assert report["summary"]["both"]["f1"] > 0.9
    assert (work / "out" / "demo.png").stat().st_size > 0 and (work / "out" / "demo.wav").stat().st_size > 44
