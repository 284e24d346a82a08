"""Where the shipped policies are: the one place any module looks for them.

`policies_dir()` is:

  1. `$DEXGUITAR_POLICIES` if set, as it is (a folder of exported policies, e.g. a copy of models/policies);
  2. else `models/policies` installed with the package, if there: the wheel ships the repository's top-level
     `models/policies` as the package data of `dexguitar_models` (pyproject.toml);
  3. else the source tree's `models/policies`, beside the `dexguitar` package (an editable install made before
     `dexguitar_models` existed, or a checkout on PYTHONPATH); a message about a missing policy names it.

Read when a module is imported (`cli.POLICIES`, `pipeline.Recipe`'s defaults): set the variable before the process
starts.
"""
from __future__ import annotations

import importlib.util
import os
from pathlib import Path

POLICIES_ENV = "DEXGUITAR_POLICIES"
PACKAGE = "dexguitar_models"          # the repository's models/ folder, installed (pyproject.toml)


def _installed() -> Path | None:
    try:
        spec = importlib.util.find_spec(PACKAGE)
    except (ImportError, ValueError):
        return None
    for folder in (spec.submodule_search_locations or []) if spec else []:
        if (Path(folder) / "policies").is_dir():
            return Path(folder) / "policies"
    return None


def policies_dir() -> Path:
    """The folder of the shipped policies (`left_general`, `right_mixed`, `gsync_<song>`, ...): see the module."""
    if os.environ.get(POLICIES_ENV):
        return Path(os.environ[POLICIES_ENV]).expanduser()
    source = Path(__file__).resolve().parents[1] / "models" / "policies"
    return _installed() or source
