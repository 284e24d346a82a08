"""Where XLA's compile time goes, pass by pass (issue 10, "compile once"): reads a log written with
`TF_CPP_MIN_LOG_LEVEL=0 TF_CPP_VMODULE=hlo_pass_pipeline=1` and prints, per module matching MODULE (default jit_chunk),
the seconds of each HLO pass summed over its runs, of the invariant checks between passes, and of each pipeline.

    python experiments/xla_passes.py LOG [MODULE] [TOP]
"""
import collections
import datetime
import json
import re
import sys

UNITS = {"us": 1e-6, "ms": 1e-3, "s": 1.0, "min": 60.0}
STAMP = re.compile(r"^[IWE](\d{4} \d\d:\d\d:\d\d\.\d+)\s+(\d+)\s+(\S+)\] (.*)$")


def seconds(text: str) -> float:
    value, unit = text.split()
    return float(value) * UNITS[unit]


def stamp(text: str) -> float:
    t = datetime.datetime.strptime(text, "%m%d %H:%M:%S.%f")
    return t.timestamp()


def parse(lines, module_re: str = "jit_chunk"):
    passes, pipelines, checks = collections.Counter(), collections.Counter(), collections.Counter()
    runs = collections.Counter()
    threads = collections.defaultdict(dict)     # the log interleaves threads that compile modules side by side
    for line in lines:
        m = STAMP.match(line)
        if not m:
            continue
        t, msg = stamp(m.group(1)), m.group(4)
        th = threads[m.group(2)]
        p = re.match(r"Running HLO pass pipeline on module (\S+): (.*)$", msg)
        if p:
            if th.get("module") and re.search(module_re, th["module"]):
                pipelines[th["pipeline"]] += th["last"] - th["start"]     # to its last pass
            th.update(module=p.group(1), pipeline=p.group(2), start=t, last=t)
            continue
        if not th.get("module") or not re.search(module_re, th["module"]):
            continue
        q = re.match(r"HLO pass: (\S+) time: (\S+ \S+) ", msg)
        if q:
            th["last"] = t
            passes[q.group(1)] += seconds(q.group(2))
            runs[q.group(1)] += 1
        elif msg.strip().startswith("Invariant checker done"):
            if th.get("check") is not None:
                checks[msg.strip().split()[-1]] += t - th["check"]
            th["check"] = None
        elif msg.strip().startswith("Invariant checker"):
            th["check"] = t
    return passes, runs, checks, pipelines


def main(path: str, module_re: str = "jit_chunk", top: int = 40) -> dict:
    with open(path, errors="replace") as f:
        passes, runs, checks, pipelines = parse(f, module_re)
    out = {"module": module_re, "passes_s": round(sum(passes.values()), 1),
           "invariant_checks_s": {k: round(v, 1) for k, v in checks.items()},
           "top_passes": [[k, round(v, 2), runs[k]] for k, v in passes.most_common(top)],
           "pipelines": [[k, round(v, 2)] for k, v in pipelines.most_common(25)]}
    return out


if __name__ == "__main__":
    a = sys.argv[1:]
    print(json.dumps(main(a[0], *(a[1:2]), *(int(x) for x in a[2:3])), indent=1))
