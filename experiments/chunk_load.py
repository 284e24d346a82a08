"""How long a kept training chunk takes to load in a new process (issue 10: a later run's chunk ready in <= 10 s):
reading its file, then `deserialize_and_load`, each timed apart, for every chunk file in `<cache>/chunks/`. One JSON
line per file.

    python experiments/chunk_load.py CACHE_DIR
"""
import json
import pickle
import sys
import time
from pathlib import Path

import jax
from jax.experimental import serialize_executable


def main(cache: str) -> None:
    jax.devices()                                   # the backend's own start, not the load's
    for path in sorted(Path(cache, "chunks").glob("chunk-*.exe")):
        t0 = time.perf_counter()
        with open(path, "rb") as f:
            payload = pickle.load(f)
        t1 = time.perf_counter()
        serialize_executable.deserialize_and_load(*payload)
        t2 = time.perf_counter()
        print(json.dumps({"file": path.name, "mb": round(path.stat().st_size / 1e6, 1), "read_s": round(t1 - t0, 2),
                          "deserialize_and_load_s": round(t2 - t1, 2), "device": jax.devices()[0].device_kind}))


if __name__ == "__main__":
    main(sys.argv[1])
