"""The env protocol shared by the left, right and duet envs: `reset(key) -> State`, `step(State, action) -> State`.

One MJX model; a `State` pytree of a few parts: the hands' physics and what is observed of it (`Body`), where in the
song the hands are (`cursor.Cursor`), the picking bookkeeping of the current note (`Picking`) and the per-note
score tally (`scoring.NoteTally`). `step` is the pure control step: physics, detection, rewards, scoring, the cursor
moved on. What happens at the end of a window or an episode (a new window chained, a time limit and auto-reset, or
stopping at the end of the song) is the business of the small wrappers in `wrappers.py`; `envs.make` composes them.

Songs arrive as a stacked `Timeline` batch and are read only through `music.cursor`. `bind(songs)` gives the same
env over other songs of the same capacities, so a jitted function that takes the songs as an argument is compiled
once for every song set.
"""
from __future__ import annotations

import dataclasses
import functools
from typing import NamedTuple

import jax
import jax.numpy as jnp
import mujoco
from flax import struct

from dexguitar import mjx as _quiet_mjx
from dexguitar.envs import rewards as R
from dexguitar.world import scoring
from dexguitar.envs.layout import ObsLayout
from dexguitar.music import cursor as CU
from dexguitar.music import timeline as TL
from dexguitar.world import detect
from dexguitar.world import hands as H
from dexguitar.world import physics as P
from dexguitar.world import scene as S
from dexguitar.world.geometry import positive_w, quat_conj, quat_mul, quat_to_mat, segment_distance
from dexguitar.world.guitar import N_STRINGS, Guitar
from dexguitar.world.physics import control_step, exact

mjx = _quiet_mjx()

HISTORY = 2                    # frames of link states in the observation (reference §4)
LINK_FEATURES = 13             # position 3, quaternion 4, linear velocity 3, angular velocity 3
# r_contact of Eq. 15: the picking hand's thumb touches its index finger where their capsules' surfaces are at most
# this far apart (m). The reference pays it for net contact forces (PhysX, contact offset 0.1 mm a shape), i.e. on
# touching; 0.2 mm, the gap at which PhysX makes that contact, leaves room for float32 rounding and stays well below
# the home pose's gap (0.98 mm thumb3 to index3), which does not touch (MuJoCo reports no contact there either).
CONTACT_TOL = 2e-4
# the picking hand's bodies (hand-prefixed) whose capsules hold the pick: the thumb's last phalanx against the index
# finger's middle and last ones (the scene's only self-contact pairs, `world.hands.hand_xml`)
GRIP_BODIES = ("thumb3", "index2", "index3")


@dataclasses.dataclass(frozen=True)
class EnvConfig:
    """Defaults reproduce the paper / reference; every field can be overridden by name."""

    episode_frames: int = 600            # 10 s at 60 Hz for one hand (reference §3.7); the duet uses 1200
    window_notes: tuple[int, int] = (10, 20)   # n ~ U{10..19}: a rest + n-1 notes per training window (§3.4)
    rest_frames: int = 5                 # grace rest at the start of every window
    count_in: int = 15                   # evaluation: the rest before a whole song's first note (0.25 s; not the
                                         # paper's, whose test loops a song: its 5-frame rest from the home pose
                                         # leaves a first note at fret 12 out of any hand's reach)
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
    even_notes: bool = False             # not in the paper: every note of a song in as many training windows as any
                                         # other, its first and last ones too (`cursor.sample_window`)
    sequential: bool = False             # evaluation: whole songs from the start, episode ends with the song
    ready_after: int = -1                # duet gate: -1 = the paper's strict gate; k >= 0 = relaxed after k frames
    hold_reward: float = 0.0             # duet, not in the paper: added to the pick column per string whose
                                         # both-hands hold (rule (3) of both-hands F1) completes in the step
    mirror: bool = False                 # the left-handed player's scene
    feedforward: bool = False            # the left action is a residual on the planner's (`planner.plans`)
    right_feedforward: bool = False      # the right action likewise, on the right planner's
    teacher: bool = False                # the hand's planner's action for its state in info["teacher"] (the left or
                                         # the right env), not added to the action: a learned hand's labels
                                         # (`TrainConfig.teacher_weight`)
    teacher_gain: float = 1.0            # the label's pull back to the plan: planned action + gain x (planned joint
                                         # position - joint position) / half range
    teacher_damping: float = 0.0         # s: + this x (planned joint velocity - joint velocity) / half range on the
    teacher_finger_damping: float = 0.0  # wrist, and this on the fingers: damping through the target, which keeps
                                         # the label playing through a student's errors (docs/results.md)
    margin_reward: float = 0.0           # not in the paper: added to each string's column times its press margin
                                         # (`rewards.margin_reward`), a smooth measure of how robustly it plays
    plan_wrist_reward: float = 0.0       # not in the paper: added to each string's column times the closeness of the
                                         # left wrist to the planner's hand position (`rewards.plan_wrist_reward`);
                                         # needs the left plans (`teacher` or `feedforward`)
    physics: str = "auto"                # MJX's "jax" or "warp" implementation; "auto": Warp on a GPU where warp-lang
                                         # is installed, else JAX (`world.physics.resolve`)
    warp_envs: int = 4096                # Warp: the most envs stepped at once; its contact buffer, which all envs
                                         # share, is sized for them (`world.physics.warp_sizes`)

    def evaluation(self) -> "EnvConfig":
        return dataclasses.replace(self, sequential=True, shift_prob=0.0, tempo_prob=0.0, pick_depth=0.0,
                                   init_noise=0.0, rest_frames=self.count_in)

    def sized(self, envs: int, devices: int = 1) -> "EnvConfig":
        """This config for `envs` envs stepped at once over `devices` devices (a training run's `num_envs`, an
        evaluation's batch of songs): under Warp, `physics` "warp" and `warp_envs` the envs of one device, which
        steps them with buffers of its own (`Placement.each`); where Warp cannot run (`world.physics.resolve`),
        `physics` "jax"; else this config itself, unchanged, so a JAX run's config (and its compiled programs' keys)
        is the same whether it was sized or not."""
        physics = P.resolve(self.physics)
        if physics == "warp":
            return dataclasses.replace(self, physics="warp", warp_envs=int(envs) // max(int(devices), 1))
        if self.physics == "warp":
            return dataclasses.replace(self, physics="jax")
        return self

    def window_args(self) -> dict:
        """The keyword arguments of `cursor.sample_window`."""
        return {k: getattr(self, k) for k in ("sequential", "window_notes", "rest_frames", "max_note_frames",
                                              "min_frames", "shift_prob", "tempo_prob", "tempo_delta",
                                              "fill_strum_gaps", "even_notes")}


@struct.dataclass
class Body:
    """The hands' physics and what is observed of it (guitar frame)."""

    data: mjx.Data
    links: jnp.ndarray         # float32 (hands, 16, 7) key-link position + quaternion
    link_hist: jnp.ndarray     # float32 (3, hands, 16, 7) the last three frames of links (discriminator input)
    hist: jnp.ndarray          # float32 (HISTORY, hands * 16 * 13) observed link features
    tips: jnp.ndarray          # float32 (hands, 5, 3) wrist + 4 fingertips (wrist frame for tips) last step


@struct.dataclass
class Picking:
    """The right hand's bookkeeping of the current note."""

    done: jnp.ndarray          # bool (6,) strings picked (or given up) in this note
    clean: jnp.ndarray         # bool (6,) no error on the string in this note (reward, critic's privileged bits)
    path: jnp.ndarray          # float32 (2, 3) the pick point one and two steps ago


@struct.dataclass
class State:
    body: Body
    cursor: CU.Cursor
    picking: Picking
    tally: scoring.NoteTally
    obs: jnp.ndarray           # float32 (obs_size,) actor observation
    privileged: jnp.ndarray    # float32 (6,) critic-only bits: strings not tackled wrongly so far in the note
    reward: jnp.ndarray        # float32 (columns,)
    done: jnp.ndarray          # bool: the episode ended with this transition
    terminated: jnp.ndarray    # bool: ended by failure (not a time-out)
    lifetime: jnp.ndarray      # int32 control steps since the reset
    key: jnp.ndarray
    info: dict                 # per-step outputs: press, picks, note_end, song, song_note, nonfinite, note scores


class Task(NamedTuple):
    """What a hand's task makes of one control step."""

    reward: jnp.ndarray        # (columns,)
    press: jnp.ndarray         # int32 (6,) detected frets (zeros without a fretting hand)
    tips: jnp.ndarray          # (hands, 5, 3)
    terminate: jnp.ndarray     # bool
    picks: jnp.ndarray         # bool (6,) strings crossed by the pick this step
    wrong: jnp.ndarray         # bool (6,) picking errors this step (the right hand's score)
    picking: Picking


# ---------------------------------------------------------------------------------------------------- the env

def _capsule(model: mujoco.MjModel, body: str) -> int:
    """The id of the one capsule geom of the body named `body`."""
    b = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, body)
    found = [g for g in range(model.ngeom)
             if b >= 0 and model.geom_bodyid[g] == b and model.geom_type[g] == mujoco.mjtGeom.mjGEOM_CAPSULE]
    if len(found) != 1:
        raise ValueError(f"body {body!r} has {len(found)} capsule geoms; expected one")
    return found[0]


class GuitarEnv:
    """One env over a scene with the given hand roles; subclasses define goals, rewards and their weights."""

    roles: tuple[str, ...] = ()
    scene: str = ""
    reward_columns: tuple[str, ...] = ()
    reward_weights: tuple[float, ...] = ()     # PPO weight of each column (Eq. 9), beside the columns they weigh

    def __init__(self, songs: TL.Timeline, config: EnvConfig = EnvConfig()):
        if songs.n_notes.ndim == 0:
            songs = TL.stack([songs])
        self.physics = P.resolve(config.physics)
        self.config = config
        self.songs = songs
        self.guitar = Guitar(mirror=config.mirror)
        self.model = S.build_model(self.scene, mirror=config.mirror)
        pos, rot = S.guitar_pose(self.model)
        self._g_pos, self._g_rot = jnp.asarray(pos, jnp.float32), jnp.asarray(rot, jnp.float32)
        self._g_quat_inv = quat_conj(jnp.asarray(S.guitar_quat(config.mirror), jnp.float32))
        lo, hi = self.model.actuator_ctrlrange.T
        self._ctrl_lo, self._ctrl_hi = jnp.asarray(lo, jnp.float32), jnp.asarray(hi, jnp.float32)
        self._ctrl_half = jnp.asarray((hi - lo) / 2, jnp.float32)
        self._home = jnp.asarray(self.model.key_qpos[0], jnp.float32)
        d = mujoco.MjData(self.model)
        mujoco.mj_resetDataKeyframe(self.model, d, 0)
        mujoco.mj_kinematics(self.model, d)
        # this process's own device: MJX's default is jax.devices()[0], which in a run of several processes
        # (`--distributed`) is the first process's, out of reach of the others
        self.mjx_model, self._data0 = P.put(self.model, d, self.physics, config.warp_envs, jax.local_devices()[0])
        self._fills = P.fills(self._data0)
        self.hands = tuple(S.hand_index(self.model, r) for r in self.roles)
        self._jnt_lo = jnp.asarray(self.model.jnt_range[:, 0], jnp.float32)
        self._jnt_hi = jnp.asarray(self.model.jnt_range[:, 1], jnp.float32)
        if "right" in self.roles:
            grip = [_capsule(self.model, S.PREFIX["right"] + b) for b in GRIP_BODIES]
            self._grip_geoms = jnp.asarray(grip, jnp.int32)
            self._grip_size = jnp.asarray(self.model.geom_size[grip, :2], jnp.float32)     # (3, 2) radius, half-length

    def bind(self, songs: TL.Timeline) -> "GuitarEnv":
        """This env over other songs of the same capacities (e.g. traced arguments of a jitted function)."""
        env = object.__new__(type(self))
        env.__dict__.update(self.__dict__, songs=songs)
        return env

    # ------------------------------------------------------------------------ sizes
    @property
    def action_size(self) -> int:
        return H.N_DOF * len(self.roles)

    @property
    def obs_size(self) -> int:
        return self.layout.obs_size

    @property
    def window_capacity(self) -> int:
        return int(self.songs.left.shape[-2]) + 1 if self.config.sequential else self.config.window_notes[1] + 1

    @functools.cached_property
    def layout(self) -> ObsLayout:
        """The observation layout, from the shapes of what `reset` observes: the link features and each hand's goal
        at a window's start. Traced on first use and without the physics (the kinematics would be a second of
        tracing per env); tests/test_envs.py checks it against the observation `reset` returns."""
        def pieces(key):
            links = jnp.zeros((len(self.hands), len(H.KEY_LINKS), 7))
            cursor, picking = CU.start(self.sample_window(key)), self.first_picking(jnp.zeros(3))
            return self.link_features(links, links), [self.hand_goal(role, cursor, picking) for role in self.roles]
        frame, goals = jax.eval_shape(pieces, jax.random.PRNGKey(0))
        if len({g.shape for g in goals}) != 1:
            raise ValueError(f"hands with goals of different sizes: {[g.shape for g in goals]}")
        return ObsLayout(roles=self.roles, history=HISTORY, frame=frame.shape[0] // len(self.roles),
                         goal=goals[0].shape[0], privileged=N_STRINGS)

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

    def to_guitar(self, points):
        return (points - self._g_pos) @ self._g_rot

    def segments(self, data, hand):
        """(12, 2, 3) finger parts of one hand in the guitar frame."""
        return self.to_guitar(S.finger_segments(data.xpos, data.site_xpos, hand))

    def wrist_and_tips(self, data, links, role_i):
        """(5, 3): wrist position (guitar frame) and the 4 fingertips relative to the wrist, in its frame."""
        tips = self.to_guitar(data.site_xpos[jnp.asarray(self.hands[role_i].tips)])
        wrist = links[role_i, 0]
        rel = (tips - wrist[:3]) @ quat_to_mat(wrist[3:])
        return jnp.concatenate([wrist[None, :3], rel], axis=0)

    def pick_point(self, data):
        return self.to_guitar(data.site_xpos[self.hands[self.roles.index("right")].pick])

    def thumb_index_gaps(self, data):
        """(2,) m: the surface distance of the picking hand's thumb3 capsule to its index2 and index3 capsules
        (segment-segment distance of their axes minus both radii; negative where they overlap), from `geom_xpos` and
        `geom_xmat`, which both MJX implementations fill in kinematics (no collision detection needed)."""
        g, size = self._grip_geoms, self._grip_size
        half = data.geom_xmat[g].reshape(-1, 3, 3)[:, :, 2] * size[:, 1:]    # capsule axis: the geom frame's z
        a, b = data.geom_xpos[g] - half, data.geom_xpos[g] + half
        d2, _, _ = segment_distance(a[0], b[0], a[1:], b[1:])
        return jnp.sqrt(jnp.maximum(d2, 1e-12)) - size[0, 0] - size[1:, 0]

    def thumb_index_contact(self, data):
        """r_contact of Eq. 15: 1 where the thumb touches the index finger to hold the pick, else 0 (the paper:
        "r_contact = 1 if the thumb and index contact with each other correctly to hold the pick or 0 otherwise").
        Touching: thumb3's capsule within `CONTACT_TOL` (0.2 mm) of index2's or index3's (`thumb_index_gaps`). The
        reference (env.py:2028-2032) pays it for any net contact force on thumb3 and on index2 or index3, from
        whatever touches them; here it is the two fingers' own contact, as the paper says. The shipped right hands
        were trained with 0 here (their contact slots were looked up in a Data before any collision)."""
        return jnp.any(self.thumb_index_gaps(data) <= CONTACT_TOL).astype(jnp.float32)

    # ------------------------------------------------------------------------ goals
    def hand_goal(self, role: str, cursor: CU.Cursor, picking: Picking):
        return CU.left_goal(cursor) if role == "left" else CU.right_goal(cursor, picking.done)

    def observe(self, body: Body, cursor: CU.Cursor, picking: Picking) -> jnp.ndarray:
        return jnp.concatenate([body.hist.reshape(-1)] + [self.hand_goal(r, cursor, picking) for r in self.roles])

    # ------------------------------------------------------------------------ reset / step
    def sample_window(self, key, song=None) -> CU.Window:
        return CU.sample_window(self.songs, key, self.window_capacity, song=song, **self.config.window_args())

    @exact
    def reset(self, key, song=None) -> State:
        k_win, k_noise, k_next = jax.random.split(key, 3)
        window = self.sample_window(k_win, song)
        home, qvel = self._home, jnp.zeros_like(self._data0.qvel)
        for role, plan in self.plans.items():   # the planned state of the window's first frame (reference state init)
            j = jnp.asarray(self.hands[self.roles.index(role)].qpos)
            f = jnp.clip(window.start, 0, plan.frames[window.song] - 1)
            home, qvel = home.at[j].set(plan.qpos[window.song, f]), qvel.at[j].set(plan.qvel[window.song, f])
        # a planned hand starts exactly on its plan: 2 cm of wrist noise mid-song cost the planner a fifth of its F1
        # (0.82 -> 0.64 on the windows of three songs); exploration comes from the policy
        scale = 0.0 if self.planned else self.config.init_noise
        noise = jax.random.uniform(k_noise, self._home.shape, minval=-1.0, maxval=1.0) * scale
        qpos = jnp.clip(home + noise, self._jnt_lo, self._jnt_hi)
        data = P.refill(self._data0, self._fills).replace(qpos=qpos, qvel=qvel, ctrl=qpos)
        data = mjx.kinematics(self.mjx_model, data)
        links = self.link_states(data)
        feats = self.link_features(links, links)
        tips = jnp.stack([self.wrist_and_tips(data, links, i) for i in range(len(self.roles))])
        pick = self.pick_point(data) if "right" in self.roles else jnp.zeros(3)
        body = Body(data=data, links=links, link_hist=jnp.stack([links] * 3), hist=jnp.stack([feats] * HISTORY),
                    tips=tips)
        cursor, picking = CU.start(window), self.first_picking(pick)
        return State(body=body, cursor=cursor, picking=picking, tally=scoring.empty_tally(),
                     obs=self.observe(body, cursor, picking), privileged=jnp.ones(N_STRINGS),
                     reward=jnp.zeros(len(self.reward_columns)), done=jnp.bool_(False),
                     terminated=jnp.bool_(False), lifetime=jnp.int32(0), key=k_next, info=self.empty_info())

    @staticmethod
    def first_picking(pick) -> Picking:
        """Nothing picked yet, the pick at rest at `pick`."""
        return Picking(done=jnp.zeros(N_STRINGS, bool), clean=jnp.ones(N_STRINGS, bool), path=jnp.stack([pick, pick]))

    def empty_info(self):
        z = jnp.zeros(6, jnp.float32)
        info = {"press": jnp.zeros(N_STRINGS, jnp.int32), "picks": jnp.zeros(N_STRINGS, bool),
                "note_end": jnp.bool_(False), "song": jnp.int32(0), "song_note": jnp.int32(0),
                "nonfinite": jnp.bool_(False), "left": z, "right": z, "both": z, "both_now": z}
        if self.config.teacher:
            info["teacher"] = jnp.zeros(H.N_DOF, jnp.float32)
        return info

    def action_to_ctrl(self, action):
        """PD targets: a = 0 holds the home pose, a = +-1 moves a joint by half its range, clipped to the range.

        The authors map a = 0 to the middle of each range (a wrist in the middle of its workspace, fingers half bent,
        far from any playing pose) and a = +-0.5 to the limits. Centring on the home pose makes an untrained policy
        start from a sensible hand and the scripted player's actions a plain (target - home) / half-range."""
        return jnp.clip(self._home + jnp.clip(action, -1.0, 1.0) * self._ctrl_half, self._ctrl_lo, self._ctrl_hi)

    @exact
    def step(self, state: State, action) -> State:
        """One control step: physics, detection, rewards, scoring, and the cursor moved on. Physics that went
        non-finite (a NaN action, an exploding contact) terminates the episode with `info["nonfinite"]` set."""
        cfg = self.config
        action = action + self.feedforward(state.cursor)
        data = control_step(self.mjx_model, state.body.data, self.action_to_ctrl(action))
        nonfinite = ~(jnp.all(jnp.isfinite(data.qpos)) & jnp.all(jnp.isfinite(data.qvel)))
        links = self.link_states(data)
        body = state.body.replace(data=data, links=links,
                                  hist=jnp.concatenate([state.body.hist[1:],
                                                        self.link_features(links, state.body.links)[None]]),
                                  link_hist=jnp.concatenate([state.body.link_hist[1:], links[None]]))
        goal_left, targets, dur = CU.current(state.cursor)
        task = self.task(state, body, goal_left, targets)
        tally = scoring.update(state.tally, task.press, goal_left, task.picks if self.picks else None, task.wrong)
        task_reward = task.reward
        if cfg.hold_reward and self.picks and "left" in self.roles:      # the duet: both hands judged together
            task_reward = task_reward.at[-1].add(
                cfg.hold_reward * jnp.sum(scoring.holds_completed(state.tally, tally, dur, targets)))

        cursor, note_end = CU.advance(state.cursor)
        info = self.empty_info()
        info.update(press=task.press, picks=task.picks, note_end=note_end & ~state.cursor.over,
                    song=state.cursor.window.song, song_note=state.cursor.window.first + state.cursor.note - 1,
                    nonfinite=nonfinite)
        if cfg.teacher:
            info["teacher"] = self.teacher(state)
        scores, fresh = scoring.close(tally, dur, goal_left, targets if self.picks else None)
        for hand, value in scores.items():
            info[hand] = jnp.where(info["note_end"], value, 0.0)
        tally = jax.tree.map(lambda a, b: jnp.where(note_end, a, b), fresh, tally)
        picking = jax.tree.map(lambda fresh, kept: jnp.where(note_end, fresh, kept),
                               task.picking.replace(done=jnp.zeros(N_STRINGS, bool),
                                                    clean=jnp.ones(N_STRINGS, bool)), task.picking)

        lifetime = state.lifetime + 1
        terminated = (task.terminate & (lifetime > cfg.grace_frames)) | nonfinite
        reward = jnp.where(terminated, cfg.terminate_reward, task_reward)
        body = body.replace(tips=task.tips)
        return state.replace(body=body, cursor=cursor, picking=picking, tally=tally,
                             obs=jnp.where(nonfinite, 0.0, self.observe(body, cursor, picking)),
                             privileged=picking.clean.astype(jnp.float32), reward=reward, done=terminated,
                             terminated=terminated, lifetime=lifetime, info=info)

    @property
    def plans(self) -> dict:
        """{role: `Plan`} of the hands that act on top of a planner's feedforward or learn from its labels (the
        songs' plans of those roles)."""
        cfg = self.config
        alone = len(self.roles) == 1                      # a teacher labels a one-hand env's hand
        found = {"left": self.songs.plan if cfg.feedforward or (cfg.teacher and alone) else None,
                 "right": self.songs.plan_right if cfg.right_feedforward or (cfg.teacher and alone) else None}
        return {r: found[r] for r in self.roles if found[r] is not None}

    @property
    def planned(self) -> bool:
        """Does a hand play along a plan (a feedforward, or a teacher's labels)? Its windows start in the planned
        state and end their episodes, so that the plan always belongs to the notes being played."""
        return bool(self.plans)

    def feedforward(self, cursor: CU.Cursor):
        """(action_size,) the planners' actions of the cursor's song frame in their hands' slices; zeros where a
        hand has no feedforward."""
        out, song = jnp.zeros(self.action_size), cursor.window.song
        for role, plan in self.plans.items():
            if not (self.config.feedforward if role == "left" else self.config.right_feedforward):
                continue                                             # a teacher's plan only labels
            ff = plan.action[song, jnp.clip(CU.song_frame(cursor), 0, plan.frames[song] - 1)]
            i = self.roles.index(role) * H.N_DOF
            out = out.at[i:i + H.N_DOF].set(ff)
        return out

    def teacher(self, state: State):
        """(27,) the hand's planner's action for this state (a one-hand env): the planned action of the song frame
        plus the PD target offset that pulls the hand back to the planned pose (`EnvConfig.teacher_gain`). The plan's
        PD targets alone already pull toward the plan at the PD's own rate; the gain stiffens that pull where the hand
        strayed, and `teacher_damping` / `teacher_finger_damping` damp the lightly damped wrist and fingers through
        the target. DAgger's expert: it labels any state a student visits, not only the planned ones."""
        cfg, plan, song, i = self.config, self.plans[self.roles[0]], state.cursor.window.song, 0
        f = jnp.clip(CU.song_frame(state.cursor), 0, plan.frames[song] - 1)
        j = jnp.asarray(self.hands[i].qpos)
        q, v = state.body.data.qpos[j], state.body.data.qvel[j]
        half = self._ctrl_half[i * H.N_DOF:(i + 1) * H.N_DOF]
        damping = jnp.where(jnp.arange(H.N_DOF) < H.WRIST_DOF, cfg.teacher_damping, cfg.teacher_finger_damping)
        label = plan.action[song, f] + (cfg.teacher_gain * (plan.qpos[song, f] - q)
                                        + damping * (plan.qvel[song, f] - v)) / half
        return jnp.clip(label, -1.0, 1.0)

    def plan_wrist(self, state: State, data):
        """`rewards.plan_wrist_reward` of the left hand after this step (`data`), against the planned hand position of
        the next song frame (a plan's pose is the one at the start of its frame)."""
        plan, song, i = self.plans["left"], state.cursor.window.song, self.roles.index("left")
        f = jnp.clip(CU.song_frame(state.cursor) + 1, 0, plan.frames[song] - 1)
        slides = jnp.asarray(self.hands[i].qpos[:3])
        return R.plan_wrist_reward(data.qpos[slides], plan.qpos[song, f, :3])

    @property
    def picks(self) -> bool:
        """Does this env pick strings (is there a right hand)?"""
        return "right" in self.roles

    def task(self, state: State, body: Body, goal_left, targets) -> Task:
        raise NotImplementedError

    # ------------------------------------------------------------------------ shared task pieces
    def hand_energy(self, state, data, links, i):
        """(tips (5, 3), Eq. 8 energy of hand i over this step)."""
        tips = self.wrist_and_tips(data, links, i)
        prev = state.body.tips[i]
        return tips, R.hand_energy((tips[0] - prev[0]) * S.CONTROL_HZ, (tips[1:] - prev[1:]) * S.CONTROL_HZ)

    def left_part(self, state, body, goal_left):
        """(reward columns (6,), r_correct, press, tips, terminate) of the fretting hand."""
        i = self.roles.index("left")
        data = body.data
        seg = self.segments(data, self.hands[i])
        press = detect.pressed_frets(seg, self.guitar)
        tips, energy = self.hand_energy(state, data, body.links, i)
        columns, correct = R.left_reward(seg, goal_left, press, energy, self.guitar)
        if self.config.margin_reward:
            columns = columns + self.config.margin_reward * R.margin_reward(seg, goal_left, self.guitar)
        if self.config.plan_wrist_reward:
            columns = columns + self.config.plan_wrist_reward * self.plan_wrist(state, data)
        thumb = self.to_guitar(data.site_xpos[self.hands[i].thumb_tip])
        return columns, correct, press, tips, R.left_failed(body.links[i, 0, :3], seg, thumb, self.guitar)

    def right_part(self, state, body, targets, ready):
        """(reward, picks, wrong, picking, tips, terminate) of the picking hand; `ready`: the duet's gate."""
        i = self.roles.index("right")
        data, p = body.data, state.picking
        pick = self.pick_point(data)
        prev, prev2 = p.path[0], p.path[1]
        picks, wrong, early, done, clean = R.pick_update(prev, pick, targets, p.done, p.clean, ready,
                                                         self.config.pick_depth, self.guitar)
        clean = jnp.where(state.lifetime < 2, p.clean, clean)        # the first frames after a reset are free
        r_pick = R.pick_reward(picks, wrong | early, targets, done, clean, ready, R.pick_distances(pick, self.guitar))
        tips, energy = self.hand_energy(state, data, body.links, i)
        v = (pick - prev) * S.CONTROL_HZ
        a = jnp.where(state.lifetime > 2, ((pick - prev) - (prev - prev2)) * S.CONTROL_HZ ** 2, 0.0)
        reward = R.right_reward(r_pick, self.thumb_index_contact(data), energy, R.pick_energy(v, a))
        hand = self.hands[i]
        points = jnp.concatenate([body.links[i, :, :3],
                                  self.to_guitar(data.site_xpos[jnp.asarray(hand.tips + (hand.thumb_tip,))])])
        picking = Picking(done=done, clean=clean, path=jnp.stack([pick, prev]))
        return reward, picks, wrong, picking, tips, R.right_failed(points, self.guitar)
