"""Reinforcement-learning environments with the Gymnasium API, on a simulated quad with its autopilot in the
loop: the agent's actions are velocity setpoints (what a companion computer sends in GUIDED), and the
simulation is on the lockstep clock, so an episode is the same for the same seed and actions.

    env = uavsim.HoverEnv()
    obs, info = env.reset(seed=1)
    obs, reward, terminated, truncated, info = env.step(env.action_space.sample())
    env.close()

Each environment runs a server of its own (several environments in one process are independent). With
Gymnasium installed they are gymnasium.Env subclasses, registered as "uavsim/Hover-v0" and
"uavsim/CameraHover-v0"; without it they work the same with uavsim.spaces.Box spaces.
"""

import math

import numpy as np

from . import _core, spaces
from .server import Server

_Base = spaces._gymnasium.Env if spaces._gymnasium is not None else object


class HoverEnv(_Base):
    """Hover at (or fly to) a target point with velocity setpoints.

    Observation (float32, 9): target minus position (ENU m), velocity (ENU m/s), roll, pitch and ENU yaw
    (rad) — from the vehicle's own telemetry, as a real drone would know them.
    Action (float32, 3): velocity setpoint in [-1, 1]^3, scaled by max_speed_m_s (ENU).
    Reward: minus the distance to the target (m) per step, minus 0.1 |action|^2; -100 when the episode
    is lost (the vehicle on the ground, disarmed, or further than max_distance_m from the target).
    terminated: lost; truncated: max_episode_s of sim time flown.

    The episode starts after take-off to takeoff_alt_m in GUIDED. target_enu_m is the target; with
    target_spread_m > 0 (the waypoint task) each episode's target is that point plus a uniform offset in
    [-spread, spread]^3 drawn from the episode's seed (its height kept at least 1 m).
    """

    metadata = {"render_modes": []}

    def __init__(self, world="empty", *, vehicle="uav0", target_enu_m=(0.0, 0.0, 3.0), target_spread_m=0.0,
                 takeoff_alt_m=3.0, action_period_s=0.1, max_episode_s=20.0, max_speed_m_s=3.0,
                 max_distance_m=30.0, lockstep_period_s=0.02, realism=None, server=None, cameras=None,
                 seed=0):
        if not 0 < action_period_s <= 10:
            raise ValueError("action_period_s must be in (0, 10] s")
        if not 0 < lockstep_period_s <= action_period_s:
            raise ValueError("lockstep_period_s must be in (0, action_period_s]")
        if not 0 < max_episode_s <= 3600:
            raise ValueError("max_episode_s must be in (0, 3600] s")
        if not 0 < max_speed_m_s <= 20:
            raise ValueError("max_speed_m_s must be in (0, 20] m/s")
        if not 0.5 <= takeoff_alt_m <= 100:
            raise ValueError("takeoff_alt_m must be in [0.5, 100] m")
        self.world = world
        self.vehicle_name = vehicle
        self.target_base_enu_m = np.asarray(target_enu_m, dtype=np.float64).reshape(3)
        self.target_spread_m = float(target_spread_m)
        self.takeoff_alt_m = float(takeoff_alt_m)
        self.action_period_s = float(action_period_s)
        self.max_steps = int(round(max_episode_s / action_period_s))
        self.max_speed_m_s = float(max_speed_m_s)
        self.max_distance_m = float(max_distance_m)
        self._server_options = dict(realism=realism, period_s=lockstep_period_s, server=server, cameras=cameras)
        self._default_seed = int(seed)
        self._rng = None
        self._server = None
        self._vehicle = None
        self._steps = 0
        self.target_enu_m = self.target_base_enu_m.copy()
        self.observation_space = spaces.box(-np.inf, np.inf, (9,), np.float32)
        self.action_space = spaces.box(-1.0, 1.0, (3,), np.float32)

    # the Gymnasium API
    def reset(self, *, seed=None, options=None):
        """Starts an episode: the world back to t = 0 with the seed, the vehicle ready, armed and at
        take-off altitude. seed None: the first episode uses the constructor's seed, later ones the next
        seed drawn from it."""
        if seed is not None:
            self._rng = np.random.default_rng(seed)
        elif self._rng is None:
            seed = self._default_seed
            self._rng = np.random.default_rng(seed)
        else:
            seed = int(self._rng.integers(0, 2**63))
        self.target_enu_m = self.target_base_enu_m.copy()
        if self.target_spread_m > 0:
            self.target_enu_m += self._rng.uniform(-self.target_spread_m, self.target_spread_m, 3)
            self.target_enu_m[2] = max(self.target_enu_m[2], 1.0)
        if self._server is None:
            self._server = Server(self.world, seed=seed, **self._server_options).start()
        else:
            self._server.reset(seed)
        self._vehicle = self._server.vehicle(self.vehicle_name)
        self._vehicle.set_mode(_core.FlightMode.GUIDED)
        self._vehicle.arm()
        self._vehicle.takeoff(self.takeoff_alt_m)
        self._on_episode_start()
        self._steps = 0
        return self._observation(), self._info()

    def step(self, action):
        if self._vehicle is None:
            raise RuntimeError("step() before reset()")
        a = np.asarray(action, dtype=np.float64)
        if a.shape != (3,) or not np.all(np.isfinite(a)):
            raise ValueError(f"action must be 3 finite numbers, not {action!r}")
        a = np.clip(a, -1.0, 1.0)
        self._vehicle.set_velocity_enu(a * self.max_speed_m_s)
        self._server.run_for(self.action_period_s)
        self._steps += 1
        t = self._vehicle.telemetry
        distance = float(np.linalg.norm(self.target_enu_m - t.position_enu_m))
        lost = (not t.armed) or t.landed == _core.LandedState.ON_GROUND or distance > self.max_distance_m
        reward = -distance - 0.1 * float(a @ a) - (100.0 if lost else 0.0)
        truncated = self._steps >= self.max_steps and not lost
        return self._observation(), reward, lost, truncated, self._info()

    def close(self):
        if self._server is not None:
            self._server.stop()
            self._server = None
            self._vehicle = None

    # for subclasses and callers
    @property
    def server(self):
        """The environment's Server (None before the first reset)."""
        return self._server

    @property
    def vehicle(self):
        return self._vehicle

    def _on_episode_start(self):
        pass

    def _state(self):
        t = self._vehicle.telemetry
        return np.concatenate([
            self.target_enu_m - t.position_enu_m,
            t.velocity_enu_m_s,
            [t.roll_rad, t.pitch_rad, _core.wrap_pi(math.pi / 2 - t.yaw_rad)],
        ]).astype(np.float32)

    def _observation(self):
        return self._state()

    def _info(self):
        t = self._vehicle.telemetry
        return {"time_s": self._server.now(), "step": self._steps, "target_enu_m": self.target_enu_m.copy(),
                "position_enu_m": np.array(t.position_enu_m), "state": self._state()}

    def __del__(self):
        if getattr(self, "_server", None) is not None:
            self.close()


class CameraHoverEnv(HoverEnv):
    """HoverEnv seen through a camera: the observation is the camera's latest image (uint8, H x W x 3, BGR)
    at the step's sim time; the vehicle's state is in info["state"]. The camera (a world camera such as
    "overview", or an onboard one) renders width x height at one frame per action period."""

    def __init__(self, world="empty", *, camera="overview", width=64, height=48, **kwargs):
        if not (8 <= width <= 4096 and 8 <= height <= 4096):
            raise ValueError("width and height must be in 8..4096 pixels")
        period = kwargs.get("action_period_s", 0.1)
        fps = 1.0 / period
        super().__init__(world, cameras={camera: f"width={width},height={height},fps={fps:g}"}, **kwargs)
        self.camera_name = camera
        self._camera = None
        self.observation_space = spaces.box(0, 255, (height, width, 3), np.uint8)

    def _on_episode_start(self):
        self._camera = self._server.camera(self.camera_name, queue=0)
        self._server.run_for(self.action_period_s)  # the first frame

    def _observation(self):
        f = self._camera.latest
        if f is None:
            return np.zeros(self.observation_space.shape, np.uint8)
        return f.image


def register_gymnasium():
    """Registers the environments with Gymnasium when it is importable (ids uavsim/Hover-v0 and
    uavsim/CameraHover-v0); nothing otherwise."""
    gym = spaces._gymnasium
    if gym is None:
        return False
    for env_id, entry in (("uavsim/Hover-v0", "uavsim.envs:HoverEnv"),
                          ("uavsim/CameraHover-v0", "uavsim.envs:CameraHoverEnv")):
        if env_id not in gym.envs.registry:
            gym.register(id=env_id, entry_point=entry)
    return True
