"""The left hand's motion line (`perform.motion_quality`): finger jerk, energy and the distance to the nearest human
pose, on synthetic trajectories whose numbers are worked out by hand. No authors' data (the capture is read only by
`dexguitar eval --human`), no compiled program."""
import numpy as np
import pytest

from dexguitar import shipped
from dexguitar.cli import main
from dexguitar.errors import UserError
from dexguitar.motion import Motion, save
from dexguitar.motion.format import joint_ranges
from dexguitar.perform import motion_quality as MQ

FPS = 60.0
rng = np.random.default_rng(0)


def poses(n: int, hand: str = "left") -> np.ndarray:
    """(n, 27) random joint values inside the hand's ranges (a motion file must hold such)."""
    lo, hi = joint_ranges(hand).T
    return rng.uniform(lo, hi, size=(n, 27))


def played(fingers: np.ndarray) -> np.ndarray:
    """(T, 27): the 21 finger joints after a wrist that moves wildly (it must not count)."""
    wrist = rng.normal(scale=5.0, size=(len(fingers), 6))
    return np.concatenate([wrist, fingers], axis=1)


def test_a_cubic_in_time_has_its_constant_third_derivative_as_jerk():
    t = np.arange(50) / FPS
    a = np.linspace(-2.0, 3.0, 21)                       # q_j(t) = a_j t^3 + t^2 - 0.5: q''' = 6 a_j
    q = a * t[:, None] ** 3 + t[:, None] ** 2 - 0.5
    assert MQ.quality(played(q), q[:1])["jerk"] == pytest.approx(6 * np.mean(np.abs(a)), rel=1e-6)


def test_energy_is_the_mean_summed_squared_velocity():
    t = np.arange(30) / FPS
    b = np.linspace(0.1, 2.1, 21)                        # q_j(t) = b_j t + 0.3: velocity b_j rad/s, no jerk
    line = MQ.quality(played(b * t[:, None] + 0.3), np.zeros((1, 21)))
    assert line["energy"] == pytest.approx(np.sum(b ** 2), rel=1e-9)
    assert line["jerk"] == pytest.approx(0.0, abs=1e-6)
    # q = t^3 on every joint: forward differences (3 t^2 + 3 t h + h^2) rad/s with h = 1/60
    t = np.arange(10) / FPS
    h = 1 / FPS
    v = 3 * t[:-1] ** 2 + 3 * t[:-1] * h + h ** 2
    line = MQ.quality(played(np.repeat(t[:, None] ** 3, 21, axis=1)), np.zeros((1, 21)))
    assert line["energy"] == pytest.approx(np.mean(21 * v ** 2), rel=1e-9)


def test_a_performance_made_of_human_frames_is_at_distance_zero():
    human = rng.uniform(-1.0, 1.5, size=(40, 21))
    q = human[rng.permutation(40)[:25]]
    assert MQ.quality(played(q), human)["human_distance"] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("c", [0.25, -0.4])
def test_a_constant_offset_from_the_only_human_frame_is_its_distance(c):
    human = rng.uniform(-1.0, 1.0, size=(1, 21))
    assert MQ.quality(played(np.repeat(human + c, 7, axis=0)), human)["human_distance"] == pytest.approx(abs(c))


def test_the_distance_is_the_median_over_played_frames():
    human = np.zeros((1, 21))
    q = np.array([0.1, 0.2, 0.5, 0.3, 0.05])[:, None] * np.ones(21)      # RMS distances 0.1 0.2 0.5 0.3 0.05
    assert MQ.quality(played(q), human)["human_distance"] == pytest.approx(0.2)


def test_nearest_neighbour_picks_the_right_frame_in_any_chunking():
    human = np.arange(30)[:, None] * np.ones(21) * 0.1                   # frames 0.1 rad apart on every joint
    perm = rng.permutation(30)
    noise = rng.uniform(-0.02, 0.02, size=(30, 21))
    for cells in (7, 61, 4_000_000):                                      # 1, 2 and all played frames per chunk
        index, rms = MQ.nearest(human[perm] + noise, human, cells=cells)
        np.testing.assert_array_equal(index, perm)
        np.testing.assert_allclose(rms, np.sqrt(np.mean(noise ** 2, axis=1)), rtol=1e-12)
    # a far frame of many: brute force agrees
    big_h, big_p = rng.normal(size=(500, 21)), rng.normal(size=(300, 21))
    brute = np.sqrt(((big_p[:, None] - big_h[None]) ** 2).mean(-1))
    index, rms = MQ.nearest(big_p, big_h, cells=1000)
    np.testing.assert_array_equal(index, brute.argmin(1))
    np.testing.assert_allclose(rms, brute.min(1), rtol=1e-12)


def test_too_short_a_performance_has_no_jerk_or_energy():
    line = MQ.quality(np.zeros((3, 27)), np.zeros((2, 27)))
    assert np.isnan(line["jerk"]) and line["energy"] == 0.0 and line["human_distance"] == 0.0
    assert np.isnan(MQ.quality(np.zeros((1, 27)), np.zeros((1, 21)))["energy"])


def test_results_get_a_line_per_song_and_a_mean():
    human = np.zeros((1, 21))
    results = {"a": {"summary": {}, "notes": [], "qpos": np.full((5, 27), 0.1)},
               "b": {"summary": {}, "notes": [], "qpos": np.full((5, 27), 0.3)}}
    mean = MQ.add_to_results(results, human)
    assert "qpos" not in results["a"] and results["b"]["summary"]["motion"]["human_distance"] == pytest.approx(0.3)
    assert mean == pytest.approx({"jerk": 0.0, "energy": 0.0, "human_distance": 0.2})


def test_human_poses_from_motion_files(tmp_path):
    q = poses(12)
    save(Motion("left", 120.0, q), tmp_path / "h.npz")
    save(Motion("left", 120.0, q[:5]), tmp_path / "h.json")
    h = MQ.human_poses([tmp_path / "h.npz", tmp_path / "h.json"])
    np.testing.assert_allclose(h, np.concatenate([q[:, 6:], q[:5, 6:]]), atol=1e-6)
    save(Motion("right", 120.0, np.zeros((3, 27))), tmp_path / "r.npz")
    with pytest.raises(UserError, match="right-hand"):
        MQ.human_poses([tmp_path / "r.npz"])


def test_a_capture_is_retargeted_once_then_read_from_the_cache(tmp_path, monkeypatch):
    from types import SimpleNamespace
    from dexguitar.motion import retarget as R
    calls = []
    q = poses(8)
    monkeypatch.setattr(R, "read_markers", lambda path: SimpleNamespace(fps=120.0))
    monkeypatch.setattr(R, "retarget", lambda markers, hands: calls.append(hands) or {"left": None})
    monkeypatch.setattr(R, "to_motion", lambda fit, fps, name: Motion("left", fps, q, name))
    csv = tmp_path / "Take.csv"
    csv.write_text("a capture\n")
    for _ in range(2):
        np.testing.assert_allclose(MQ.human_poses([csv], cache=tmp_path / "cache"), q[:, 6:], atol=1e-6)
    assert calls == [("left",)] and len(list((tmp_path / "cache").glob("Take-*-left.npz"))) == 1
    csv.write_text("another capture\n")                                   # other bytes: retargeted again
    MQ.human_poses([csv], cache=tmp_path / "cache")
    assert len(calls) == 2


def test_eval_human_refuses_a_right_hand_and_a_missing_file_before_playing(tmp_path, capsys):
    policies = shipped.policies_dir()
    assert main(["eval", "--ckpt", str(policies / "right_general"), "--song", "ode_to_joy",
                 "--human", str(tmp_path / "h.npz")]) == 2
    assert "right hand" in capsys.readouterr().err
    assert main(["eval", "--ckpt", str(policies / "left_general"), "--song", "ode_to_joy",
                 "--human", str(tmp_path / "missing.csv")]) == 2
    assert "missing.csv" in capsys.readouterr().err
