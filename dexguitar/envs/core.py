"""The env protocol shared by the left, right and duet envs: `reset(key) -> State`, `step(State, action) -> State`.

One MJX model; a `State` pytree holding the MJX data, the observation history, the notes being played (a window of a
song) and the per-note bookkeeping. Everything is jit- and vmap-able with no Python control flow on traced values:
finished envs reset inside `step`, and a window that runs out is replaced by a new one without a reset (training).

Songs arrive as a stacked `Timeline` batch (`music.timeline.stack`). Training samples windows: a 5-frame rest then
10-19 consecutive notes of a random song, with random fret shift and tempo change, note durations capped at 50
frames (reference §3.4). Evaluation (`sequential=True`) plays one whole song from its start and ends with it.
"""
from __future__ import annotations

import dataclasses

import jax
import jax.numpy as jnp
import mujoco
import numpy as np
from flax import struct
from dexguitar import mjx as _quiet_mjx

from dexguitar.envs import rewards as R
from dexguitar.music import timeline as TL
from dexguitar.perform import metrics as M
from dexguitar.world import detect
from dexguitar.world import hands as H
from dexguitar.world import scene as S
from dexguitar.world.guitar import N_FRETS, Guitar

mjx = _quiet_mjx()

N_STRINGS = 6
HISTORY = 2                    # frames of link states in the observation (reference §4)
LINK_FEATURES = 13             # position 3, quaternion 4, linear velocity 3, angular velocity 3


@dataclasses.dataclass(frozen=True)
class EnvConfig:
    """Defaults reproduce the paper / reference; every field can be overridden by name."""

    episode_frames: int = 600            # 10 s at 60 Hz for one hand (reference §3.7); the duet uses 1200
    window_notes: tuple[int, int] = (10, 20)   # n ~ U{10..19}: a rest + n-1 notes per training window (§3.4)
    rest_frames: int = 5                 # grace rest at the start of every window
    max_note_frames: int = 50            # training notes are capped at 50 frames (§3.3)
    min_frames: int = 5                  # the shortest note lasts at least 5 frames (§3.3)
    shift_prob: float = 0.5              # fret-shift augmentation, keeping the chord shape (paper Sec. 6)
    tempo_prob: float = 0.5              # tempo augmentation
    tempo_delta: int = 20                # +-20 BPM (paper Sec. 6)
    terminate_reward: float = -25.0      # every reward column of a terminated transition (§8)
    grace_frames: int = 5                # no termination during the first frames after a reset (§8)
    pick_depth: float = 0.001            # a valid pick passes >= 1 mm below the string in training (§5.2)
    init_noise: float = 0.02             # uniform noise on the home pose at reset (m / rad)
    fill_strum_gaps: bool = True         # strings between the outer targets of a strum are targets too (§3.6)
    sequential: bool = False             # evaluation: whole songs from the start, episode ends with the song
    ready_after: int = -1                # duet gate: -1 = the paper's strict gate; k >= 0 = relaxed after k frames
    mirror: bool = False                 # the left-handed player's scene

    def evaluation(self) -> "EnvConfig":
        return dataclasses.replace(self, sequential=True, shift_prob=0.0, tempo_prob=0.0, pick_depth=0.0,
                                   init_noise=0.0)


@struct.dataclass
class Window:
    """The notes being played: row 0.. n-1 valid. left: left-hand goal code; pick: right-hand targets; dur: frames."""

    left: jnp.ndarray      # int32 (W, 6)
    pick: jnp.ndarray      # bool (W, 6)
    frets: jnp.ndarray     # int32 (W, 6) what sounds (MUTE -1, OPEN 0, fret k)
    dur: jnp.ndarray       # int32 (W,)
    n: jnp.ndarray         # int32 ()
    song: jnp.ndarray      # int32 () index of the song in the batch
    first: jnp.ndarray     # int32 () song note index of row 1 (row 0 is the grace rest)


@struct.dataclass
class State:
    data: mjx.Data
    obs: jnp.ndarray           # float32 (obs_size,) actor observation
    privileged: jnp.ndarray    # float32 (6,) right-hand critic bits (strings not tackled wrongly so far)
    reward: jnp.ndarray        # float32 (columns,)
    done: jnp.ndarray          # bool: the episode ended with this transition (the state is already reset)
    terminated: jnp.ndarray    # bool: ended by failure (not a time-out)
    links: jnp.ndarray         # float32 (hands, 16, 7) current link position + quaternion (guitar frame)
    link_hist: jnp.ndarray     # float32 (3, hands, 16, 7) the last three frames of links (discriminator input)
    hist: jnp.ndarray          # float32 (HISTORY, hands * 16 * 13)
    window: Window
    note: jnp.ndarray          # int32 current row of the window
    note_frame: jnp.ndarray    # int32 frames elapsed in the current note
    lifetime: jnp.ndarray      # int32 control steps since the reset
    key: jnp.ndarray
    picked: jnp.ndarray        # bool (6,) strings picked or skipped in this note
    pick_ok: jnp.ndarray       # bool (6,) no error on the string in this note
    pick_hist: jnp.ndarray     # float32 (2, 3) pick position one and two steps ago
    tips: jnp.ndarray          # float32 (hands, 5, 3) wrist + 4 fingertips (wrist frame for tips) last step
    tally: M.NoteTally
    info: dict                 # per-step outputs: press (6,), picks (6,), note_end, per-hand note scores


# ---------------------------------------------------------------------------------------------------- quaternions

def quat_mul(a, b):
    w1, x1, y1, z1 = jnp.moveaxis(a, -1, 0)
    w2, x2, y2, z2 = jnp.moveaxis(b, -1, 0)
    return jnp.stack([w1 * w2 - x1 * x2 - y1 * y2 - z1 * z2, w1 * x2 + x1 * w2 + y1 * z2 - z1 * y2,
                      w1 * y2 - x1 * z2 + y1 * w2 + z1 * x2, w1 * z2 + x1 * y2 - y1 * x2 + z1 * w2], axis=-1)


def quat_conj(q):
    return q * jnp.array([1.0, -1.0, -1.0, -1.0])


def positive_w(q):
    return jnp.where(q[..., :1] < 0, -q, q)


def quat_to_mat(q):
    w, x, y, z = jnp.moveaxis(q, -1, 0)
    return jnp.stack([jnp.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
                      jnp.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
                      jnp.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1)], -2)


# ---------------------------------------------------------------------------------------------------- the env

class GuitarEnv:
    """One env over a scene with the given hand roles; subclasses define goals and rewards."""

    roles: tuple[str, ...] = ()
    scene: str = ""
    reward_columns: tuple[str, ...] = ()

    def __init__(self, songs: TL.Timeline, config: EnvConfig = EnvConfig(), backend: str = "jax"):
        if songs.n_notes.ndim == 0:
            songs = TL.stack([songs])
        self.config = config
        self.songs = songs
        self.guitar = Guitar(mirror=config.mirror)
        self.model = S.build_model(self.scene, mirror=config.mirror)
        self.mjx_model = mjx.put_model(self.model, impl=backend)
        self.hands = tuple(S.hand_index(self.model, r) for r in self.roles)
        pos, rot = S.guitar_pose(self.model)
        self._g_pos, self._g_rot = jnp.asarray(pos, jnp.float32), jnp.asarray(rot, jnp.float32)
        self._g_quat_inv = quat_conj(jnp.asarray(S.guitar_quat(config.mirror), jnp.float32))
        lo, hi = self.model.actuator_ctrlrange.T
        self._ctrl_mid = jnp.asarray((lo + hi) / 2, jnp.float32)
        self._ctrl_half = jnp.asarray((hi - lo) / 2, jnp.float32)
        self._home = jnp.asarray(self.model.key_qpos[0], jnp.float32)
        d = mujoco.MjData(self.model)
        mujoco.mj_resetDataKeyframe(self.model, d, 0)
        mujoco.mj_kinematics(self.model, d)
        self._data0 = mjx.put_data(self.model, d, impl=backend)
        self._jnt_lo = jnp.asarray(self.model.jnt_range[:, 0], jnp.float32)
        self._jnt_hi = jnp.asarray(self.model.jnt_range[:, 1], jnp.float32)
        self._contact_pairs = self._pick_contacts()
        n_notes = np.asarray(songs.n_notes)
        self._song_logits = jnp.log(jnp.asarray(np.maximum(n_notes, 1), jnp.float32))
        self.window_capacity = (int(songs.left.shape[1]) + 1 if config.sequential
                                else config.window_notes[1] + 1)

    # ------------------------------------------------------------------------ sizes
    @property
    def action_size(self) -> int:
        return H.N_DOF * len(self.roles)

    @property
    def n_links(self) -> int:
        return len(H.KEY_LINKS) * len(self.roles)

    goal_size: int = 0

    @property
    def obs_size(self) -> int:
        return HISTORY * self.n_links * LINK_FEATURES + self.goal_size

    # ------------------------------------------------------------------------ windows
    def sample_window(self, key, song=None) -> Window:
        """Training: a rest + n-1 notes from a random song, augmented. Sequential: a rest, then song `song` from
        its start (the authors' grace rest: the first note is not judged before the hand has had time to move)."""
        cfg, s = self.config, self.songs
        W = self.window_capacity
        k_song, k_len, k_start, k_shift, k_tempo, k_p1, k_p2 = jax.random.split(key, 7)
        if song is None:
            song = jax.random.categorical(k_song, self._song_logits)
        song = jnp.asarray(song, jnp.int32)
        n_song = s.n_notes[song]
        lead = 1                                                    # row 0 of every window is the rest
        if cfg.sequential:
            n, start = n_song, jnp.int32(0)
        else:
            n = jnp.minimum(jax.random.randint(k_len, (), cfg.window_notes[0], cfg.window_notes[1]) - 1, n_song)
            start = jax.random.randint(k_start, (), 0, jnp.maximum(n_song - n, 0) + 1)
        j = jnp.arange(W - lead)
        valid = j < n
        idx = jnp.clip(start + j, 0, s.left.shape[1] - 1)
        take = lambda x, fill: jnp.where(valid.reshape((-1,) + (1,) * (x.ndim - 2)), x[song][idx], fill)  # noqa
        left, pick, frets = take(s.left, 0), take(s.pick, False), take(s.frets, -1)
        ticks = jnp.where(valid, s.ticks[song][idx], 0)
        # Tempo: rounded so the shortest note of the window lasts a whole number of frames (>= min_frames).
        tempo = s.base_tempo[song]
        if not cfg.sequential:
            bump = jax.random.randint(k_tempo, (), -cfg.tempo_delta, cfg.tempo_delta + 1)
            tempo = jnp.where(jax.random.uniform(k_p2) < cfg.tempo_prob, jnp.maximum(tempo + bump, 30.0), tempo)
        shortest = jnp.min(jnp.where(valid, ticks, jnp.iinfo(jnp.int32).max))
        x = (shortest * (240 * 60)).astype(jnp.float32) / (s.ticks_per_whole[song].astype(jnp.float32) * tempo)
        n_short = jnp.maximum(jnp.round(x), cfg.min_frames).astype(jnp.int32)
        cum = jnp.concatenate([jnp.zeros(1, jnp.int32), jnp.cumsum(ticks)])
        onset = TL._round_ratio(cum, n_short, shortest)
        dur = jnp.where(valid, jnp.diff(onset), 0)
        if not cfg.sequential:
            dur = jnp.minimum(dur, cfg.max_note_frames)
            # Fret shift keeping the chord shape: an offset that keeps every pressed fret on the neck.
            pressed = valid[:, None] & (left > 0)
            lo = 1 - jnp.min(jnp.where(pressed, left, N_FRETS))
            hi = N_FRETS - jnp.max(jnp.where(pressed, left, 1))
            offset = jnp.where(jax.random.uniform(k_p1) < cfg.shift_prob,
                               jax.random.randint(k_shift, (), lo, hi + 1), 0)
            offset = jnp.where(jnp.any(pressed), offset, 0)
            left = jnp.where(left > 0, left + offset, left)
            frets = jnp.where(frets > 0, frets + offset, frets)
        rest = lambda x, v: jnp.concatenate([jnp.full((1,) + x.shape[1:], v, x.dtype), x])  # noqa: E731
        left, pick, frets = rest(left, 0), rest(pick, False), rest(frets, -1)
        dur = rest(dur, cfg.rest_frames)
        n = n + 1
        if cfg.fill_strum_gaps:
            i = jnp.arange(N_STRINGS)
            first = jnp.min(jnp.where(pick, i, N_STRINGS), axis=1, keepdims=True)
            last = jnp.max(jnp.where(pick, i, -1), axis=1, keepdims=True)
            pick = (i >= first) & (i <= last)
        return Window(left, pick, frets, dur.astype(jnp.int32), n.astype(jnp.int32), song, start)

    # ------------------------------------------------------------------------ observation pieces
    def link_states(self, data):
        """(hands, 16, 7): position and quaternion (w >= 0) of the key links in the guitar frame."""
        out = []
        for h in self.hands:
            b = jnp.asarray(h.key_bodies)
            pos = (data.xpos[b] - self._g_pos) @ self._g_rot
            quat = positive_w(quat_mul(self._g_quat_inv, data.xquat[b]))
            out.append(jnp.concatenate([pos, quat], axis=-1))
        return jnp.stack(out)

    def link_features(self, links, prev_links):
        """(hands * 16 * 13,) with velocities by finite difference over one control step."""
        fps = S.CONTROL_HZ
        vel = (links[..., :3] - prev_links[..., :3]) * fps
        dq = positive_w(quat_mul(links[..., 3:], quat_conj(prev_links[..., 3:])))
        ang = 2.0 * dq[..., 1:] * fps
        return jnp.concatenate([links, vel, ang], axis=-1).reshape(-1)

    def segments(self, data, hand):
        """(12, 2, 3) finger parts of one hand in the guitar frame."""
        seg = S.finger_segments(data.xpos, data.site_xpos, hand)
        return (seg - self._g_pos) @ self._g_rot

    def wrist_and_tips(self, data, links, role_i):
        """(5, 3): wrist position (guitar frame) and the 4 fingertips relative to the wrist, in its frame."""
        hand = self.hands[role_i]
        tips = (data.site_xpos[jnp.asarray(hand.tips)] - self._g_pos) @ self._g_rot
        wrist = links[role_i, 0]
        rel = (tips - wrist[:3]) @ quat_to_mat(wrist[3:])
        return jnp.concatenate([wrist[None, :3], rel], axis=0)

    def pick_point(self, data):
        hand = self.hands[self.roles.index("right")]
        return (data.site_xpos[hand.pick] - self._g_pos) @ self._g_rot

    def _pick_contacts(self):
        """Contact slots of the thumb-index pairs (r_contact of Eq. 15)."""
        if "right" not in self.roles:
            return None
        names = [mujoco.mj_id2name(self.model, mujoco.mjtObj.mjOBJ_GEOM, g) for g in range(self.model.ngeom)]
        thumb = names.index("rh_thumb3")
        index = {names.index("rh_index2"), names.index("rh_index3")}
        g = np.asarray(self._data0._impl.contact.geom)
        slots = [k for k, (a, b) in enumerate(g) if {a, b} & {thumb} and {a, b} & index]
        return jnp.asarray(slots, jnp.int32)

    def thumb_index_contact(self, data):
        contact = data._impl.contact
        return jnp.any(contact.dist[self._contact_pairs] < 1e-3).astype(jnp.float32)

    # ------------------------------------------------------------------------ goals
    def current_rows(self, state_window, note):
        """Rows note..note+4 (clipped) and their validity."""
        j = note + jnp.arange(TL.GOAL_NOTES)
        valid = j < state_window.n
        return jnp.minimum(j, self.window_capacity - 1), valid

    def timers(self, window, rows, valid, note_frame):
        """Timer codes: frames left in the current note, then the upcoming notes' full durations."""
        frames = jnp.where(valid, window.dur[rows], 0).at[0].add(-note_frame)
        return TL.timer_code(jnp.where(valid, frames, 0))

    def left_goal(self, window, note, note_frame):
        rows, valid = self.current_rows(window, note)
        return TL.goal_vector(TL.fret_code(window.left[rows]), valid, self.timers(window, rows, valid, note_frame))

    def right_goal(self, window, note, note_frame, picked):
        rows, valid = self.current_rows(window, note)
        flags = window.pick[rows].at[0].set(window.pick[rows][0] & ~picked)
        return TL.goal_vector(flags.astype(jnp.float32), valid, self.timers(window, rows, valid, note_frame))

    def goal(self, state) -> jnp.ndarray:
        raise NotImplementedError

    # ------------------------------------------------------------------------ reset / step
    def reset(self, key, song=None) -> State:
        k_win, k_noise, k_next = jax.random.split(key, 3)
        noise = jax.random.uniform(k_noise, self._home.shape, minval=-1.0, maxval=1.0) * self.config.init_noise
        qpos = jnp.clip(self._home + noise, self._jnt_lo, self._jnt_hi)
        data = self._data0.replace(qpos=qpos, qvel=jnp.zeros_like(self._data0.qvel), ctrl=qpos)
        data = mjx.kinematics(self.mjx_model, data)
        links = self.link_states(data)
        feats = self.link_features(links, links)
        window = self.sample_window(k_win, song)
        picked = jnp.zeros(N_STRINGS, bool)
        tips = jnp.stack([self.wrist_and_tips(data, links, i) for i in range(len(self.roles))])
        pick = self.pick_point(data) if "right" in self.roles else jnp.zeros(3)
        state = State(
            data=data, obs=jnp.zeros(self.obs_size), privileged=jnp.ones(N_STRINGS),
            reward=jnp.zeros(len(self.reward_columns)), done=jnp.bool_(False), terminated=jnp.bool_(False),
            links=links, link_hist=jnp.stack([links] * 3), hist=jnp.stack([feats] * HISTORY), window=window,
            note=jnp.int32(0),
            note_frame=jnp.int32(0), lifetime=jnp.int32(0), key=k_next, picked=picked,
            pick_ok=jnp.ones(N_STRINGS, bool), pick_hist=jnp.stack([pick, pick]), tips=tips,
            tally=M.empty_tally(), info=self.empty_info())
        return state.replace(obs=self.observe(state))

    def empty_info(self):
        z = jnp.zeros(6, jnp.float32)
        return {"press": jnp.zeros(N_STRINGS, jnp.int32), "picks": jnp.zeros(N_STRINGS, bool),
                "note_end": jnp.bool_(False), "song": jnp.int32(0), "song_note": jnp.int32(0),
                "left": z, "right": z, "both": z}

    def observe(self, state: State) -> jnp.ndarray:
        return jnp.concatenate([state.hist.reshape(-1), self.goal(state)])

    def action_to_ctrl(self, action):
        """PD targets: a = 0 holds the home pose, a = +-1 moves a joint by half its range, clipped to the range.

        The authors map a = 0 to the middle of each range (a wrist in the middle of its workspace, fingers half bent,
        far from any playing pose) and a = +-0.5 to the limits. Centring on the home pose makes an untrained policy
        start from a sensible hand and the scripted player's actions a plain (target - home) / half-range."""
        lo, hi = self._ctrl_mid - self._ctrl_half, self._ctrl_mid + self._ctrl_half
        return jnp.clip(self._home + jnp.clip(action, -1.0, 1.0) * self._ctrl_half, lo, hi)

    def ctrl_to_action(self, ctrl):
        """The action whose PD targets are `ctrl` (inside the joint ranges)."""
        return (ctrl - self._home) / self._ctrl_half

    def physics(self, data, action):
        ctrl = self.action_to_ctrl(action)
        data = data.replace(ctrl=ctrl)
        return jax.lax.fori_loop(0, S.SUBSTEPS, lambda _, d: mjx.step(self.mjx_model, d), data)

    def step(self, state: State, action) -> State:
        """One control step: physics, detection, rewards, bookkeeping, then reset if the episode ended."""
        cfg = self.config
        data = self.physics(state.data, action)
        links = self.link_states(data)
        feats = self.link_features(links, state.links)
        hist = jnp.concatenate([state.hist[1:], feats[None]])
        window, note = state.window, state.note
        rows, _ = self.current_rows(window, note)
        goal_left = window.left[rows[0]]
        targets = window.pick[rows[0]] & (note < window.n)

        out = self.task(state, data, links, goal_left, targets)     # rewards, presses, picks, termination
        tally = M.update(state.tally, out["press"], goal_left, out.get("picks"), out.get("wrong"))

        # Advance the note; close its tally at its last frame.
        note_frame = state.note_frame + 1
        note_end = note_frame >= window.dur[rows[0]]
        scores = M.close(tally, window.dur[rows[0]], goal_left, targets if "right" in self.roles else None)
        info = self.empty_info()
        info.update(press=out["press"], note_end=note_end & (note < window.n), song=window.song,
                    song_note=window.first + note - 1)
        if "picks" in out:
            info["picks"] = out["picks"]
        for hand, value in scores.items():
            info[hand] = jnp.where(info["note_end"], value, 0.0)
        note = jnp.where(note_end, note + 1, note)
        note_frame = jnp.where(note_end, 0, note_frame)
        tally = jax.tree.map(lambda a, b: jnp.where(note_end, a, b), M.empty_tally(), tally)
        picked = jnp.where(note_end, False, out.get("picked", state.picked))
        pick_ok = jnp.where(note_end, True, out.get("pick_ok", state.pick_ok))

        lifetime = state.lifetime + 1
        terminated = out["terminate"] & (lifetime > cfg.grace_frames)
        song_over = note >= window.n
        if cfg.sequential:
            truncated = song_over
        else:
            truncated = lifetime >= cfg.episode_frames
            # chain a new window without a reset when this one is played out
            key, k_win = jax.random.split(state.key)
            fresh = self.sample_window(k_win)
            window = jax.tree.map(lambda a, b: jnp.where(song_over, a, b), fresh, window)
            note = jnp.where(song_over, 0, note)
            state = state.replace(key=key)
        reward = jnp.where(terminated, cfg.terminate_reward, out["reward"])
        stepped = state.replace(
            data=data, reward=reward, done=terminated | truncated, terminated=terminated, links=links, hist=hist,
            link_hist=jnp.concatenate([state.link_hist[1:], links[None]]),
            window=window, note=note, note_frame=note_frame, lifetime=lifetime, picked=picked, pick_ok=pick_ok,
            pick_hist=out.get("pick_hist", state.pick_hist), tips=out["tips"], tally=tally, info=info,
            privileged=pick_ok.astype(jnp.float32))
        stepped = stepped.replace(obs=self.observe(stepped))
        # Auto-reset: the returned state of a finished episode is the next episode's first state.
        key, k_reset = jax.random.split(stepped.key)
        fresh = self.reset(k_reset).replace(reward=reward, done=stepped.done, terminated=terminated, info=info)
        stepped = stepped.replace(key=key)
        if cfg.sequential:         # evaluation envs stop at the end of their song (the caller masks by `done`)
            return stepped
        return jax.tree.map(lambda a, b: jnp.where(stepped.done, a, b), fresh, stepped)

    def task(self, state, data, links, goal_left, targets) -> dict:
        raise NotImplementedError

    # ------------------------------------------------------------------------ shared task pieces
    def left_part(self, state, data, links, goal_left):
        i = self.roles.index("left")
        seg = self.segments(data, self.hands[i])
        press = detect.pressed_frets(seg, self.guitar)
        tips = self.wrist_and_tips(data, links, i)
        prev = state.tips[i]
        energy = R.hand_energy((tips[0] - prev[0]) * S.CONTROL_HZ, (tips[1:] - prev[1:]) * S.CONTROL_HZ)
        columns, correct = R.left_reward(seg, goal_left, press, energy, self.guitar)
        return dict(press=press, reward=columns, correct=correct, tips=tips,
                    terminate=self.left_failed(links[i], seg, data))

    def left_failed(self, links, seg, data):
        """Reference §3.7: wrist outside its box, a finger wrapped far behind the neck, a fingertip sunk into the
        neck, or the thumb over the treble side of the neck."""
        w = links[0, :3]
        x = w[0] * self.guitar.sign
        out_of_box = (x < -0.1) | (x > 0.3) | (w[1] < -0.3) | (w[1] > 0.3) | (w[2] < -0.2) | (w[2] > 0.05)
        deep = jnp.any(seg[..., 2] < -0.07)
        tips = seg[2::3, 1]
        sunk = jnp.any((jnp.abs(tips[:, 0]) < 0.024) & (tips[:, 2] < self.guitar.fretboard_z - 0.003)
                       & (tips[:, 2] > -0.008))
        thumb = (data.site_xpos[self.hands[self.roles.index("left")].thumb_tip] - self._g_pos) @ self._g_rot
        return out_of_box | deep | sunk | (thumb[0] * self.guitar.sign > 0.07)

    def right_part(self, state, data, links, targets, ready):
        i = self.roles.index("right")
        cfg = self.config
        pick = self.pick_point(data)
        prev, prev2 = state.pick_hist[0], state.pick_hist[1]
        picks, wrong, picked, ok = R.pick_update(prev, pick, targets, state.picked, state.pick_ok, ready,
                                                 cfg.pick_depth, self.guitar)
        ok = jnp.where(state.lifetime < 2, state.pick_ok, ok)    # the first frames after a reset are free
        dist = R.pick_distances(pick, self.guitar)
        r_pick = R.pick_reward(picks, wrong, targets, picked, ok, ready, dist)
        tips = self.wrist_and_tips(data, links, i)
        prev_tips = state.tips[i]
        energy = R.hand_energy((tips[0] - prev_tips[0]) * S.CONTROL_HZ, (tips[1:] - prev_tips[1:]) * S.CONTROL_HZ)
        v = (pick - prev) * S.CONTROL_HZ
        a = ((pick - prev) - (prev - prev2)) * S.CONTROL_HZ ** 2
        a = jnp.where(state.lifetime > 2, a, 0.0)
        reward = (r_pick + 0.05 * self.thumb_index_contact(data)
                  + 0.05 * (energy + R.pick_energy(v, a)))                                         # Eq. 15
        pts = links[i, :, :3]
        tip_pts = (data.site_xpos[jnp.asarray(self.hands[i].tips + (self.hands[i].thumb_tip,))]
                   - self._g_pos) @ self._g_rot
        allp = jnp.concatenate([pts, tip_pts])
        x = allp[:, 0] * self.guitar.sign
        failed = jnp.any((x < -0.3) | (x > 0.3) | (allp[:, 1] < -0.6) | (allp[:, 1] > 0.0)
                         | (allp[:, 2] < -0.1) | (allp[:, 2] > 0.3))                                # §3.7
        return dict(picks=picks, wrong=wrong, picked=picked, pick_ok=ok, reward=reward, tips=tips,
                    pick_hist=jnp.stack([pick, prev]), terminate=failed)
