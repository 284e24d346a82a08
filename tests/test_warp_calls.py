"""A chunk file names Warp's FFI targets and the ids of their calls (`world.warp_calls`): a process that loads it
describes those calls as the process that traced it had, and refuses where its own targets stand elsewhere."""
import pickle

import pytest

from dexguitar.world import warp_calls as W


class Desc:
    def __init__(self, static_inputs):
        self.static_inputs = static_inputs


class Target:
    """What `warp_calls` reads of Warp's callable: its name, next call id and the calls' static arguments."""

    def __init__(self, name):
        self.name, self.call_id, self.call_descriptors = name, 0, {}

    def call(self, **static):
        self.call_descriptors[self.call_id] = Desc(static)
        self.call_id += 1


class Process:
    """One process's registry of targets, each with what it wraps."""

    def __init__(self, monkeypatch):
        self.targets = {}
        monkeypatch.setattr(W, "_targets", lambda: dict(self.targets))
        monkeypatch.setattr(W, "FfiCallDesc", Desc)

    def target(self, name, what="forward/160"):
        if name not in self.targets:
            self.targets[name] = (what, Target(name))
        return self.targets[name][1]


@pytest.fixture
def recorded(monkeypatch):
    """The record of a chunk's trace: two calls of `fwd_0` traced before it (the first state's shapes), then the
    chunk calling `step_1` three times and `fwd_0` once."""
    a = Process(monkeypatch)
    for _ in range(2):
        a.target("fwd_0").call(nworld=4)
    before = W.counts()
    for _ in range(3):
        a.target("step_1", "step/170").call(nworld=4, sparse=False)
    a.target("fwd_0").call(nworld=4)
    return pickle.loads(pickle.dumps(W.taken(before)))      # as the chunk file keeps it


def test_what_a_trace_added_is_recorded(recorded):
    assert recorded == {
        "fwd_0": {"what": "forward/160", "first": 2, "next": 3, "calls": {2: {"nworld": 4}}},
        "step_1": {"what": "step/170", "first": 0, "next": 3,
                   "calls": {i: {"nworld": 4, "sparse": False} for i in range(3)}}}


def test_a_process_that_traced_the_same_before_serves_the_calls(recorded, monkeypatch):
    b = Process(monkeypatch)
    for _ in range(2):
        b.target("fwd_0").call(nworld=4)
    registered = []

    def one_step():                         # the stand-in trace: one step, which also calls forward
        registered.append(1)
        b.target("step_1", "step/170").call(nworld=4, sparse=False)
        b.target("fwd_0").call(nworld=4)
    assert W.restore(recorded, one_step) and registered == [1]
    step, fwd = b.targets["step_1"][1], b.targets["fwd_0"][1]
    assert (step.call_id, fwd.call_id) == (3, 3)        # a later trace numbers its calls as the recording one did
    assert {i: d.static_inputs for i, d in step.call_descriptors.items()} == {
        i: {"nworld": 4, "sparse": False} for i in range(3)}
    assert fwd.call_descriptors[2].static_inputs == {"nworld": 4}


def test_a_process_that_traced_otherwise_refuses(recorded, monkeypatch):
    c = Process(monkeypatch)
    for _ in range(3):                      # one call more than the recording process before the chunk
        c.target("fwd_0").call(nworld=4)
    assert not W.restore(recorded, lambda: pytest.fail("registered targets it will not use"))

    d = Process(monkeypatch)
    for _ in range(2):
        d.target("fwd_0").call(nworld=4)
    # the stand-in trace registers another function under the recorded name
    assert not W.restore(recorded, lambda: d.target("step_1", "collision/40").call(nworld=4))

    e = Process(monkeypatch)
    for _ in range(2):
        e.target("fwd_0").call(nworld=4)
    assert not W.restore(recorded, lambda: None)        # the stand-in trace registers nothing


def test_no_warp_calls_need_nothing(monkeypatch):
    Process(monkeypatch)
    assert W.taken(W.counts()) == {}
    assert W.restore({}, lambda: pytest.fail("nothing to register"))
