"""uavsim for Python: the C++ client library (vehicles over MAVLink, cameras, radio, switches, the event loop
with its lockstep clock), world control over the sim API, a launcher for uavsim-server and RL environments.

    import uavsim
    with uavsim.Server("empty") as sim:
        uav = sim.vehicle("uav0")
        uav.set_mode(uavsim.FlightMode.GUIDED)
        uav.arm()
        uav.takeoff(5.0)
        uav.goto_local_enu([10, 0, 5])
        uav.wait_position_enu([10, 0, 5], 0.5, 30.0)
        uav.land(wait=True)

Failures raise UavsimError (its .code an Error); blocking calls release the GIL.
"""

from ._core import (
    ConnectionError,
    Error,
    EventLoop,
    FlightMode,
    Geodetic,
    GeodeticOrigin,
    InvalidArgumentError,
    LandedState,
    LoopConfig,
    MissionItem,
    Radio,
    RadioFrame,
    SimConnection,
    SimMessage,
    Switches,
    SwitchState,
    Telemetry,
    TimeoutError,
    UavsimError,
    Vehicle,
    enu_from_geodetic,
    geodetic_from_enu,
    geodetic_from_ned,
    mode_name,
    ned_from_geodetic,
    wrap_pi,
)

try:  # the camera (frames as numpy arrays) is there when the client library was built with OpenCV
    from ._core import Camera, CameraFormat, CameraIntrinsics, CameraPose, Frame, SegmentationObject
except ImportError:  # pragma: no cover - a client library without OpenCV
    pass
from .envs import CameraHoverEnv, HoverEnv, register_gymnasium
from .server import Server, find_server
from .sim import Sim

__all__ = [
    "Camera", "CameraFormat", "CameraIntrinsics", "CameraPose", "ConnectionError", "Error", "EventLoop", "FlightMode", "Frame", "Geodetic",
    "GeodeticOrigin", "InvalidArgumentError", "LandedState", "LoopConfig", "MissionItem", "Radio", "RadioFrame",
    "SegmentationObject", "SimConnection", "SimMessage", "Switches", "SwitchState", "Telemetry", "TimeoutError", "UavsimError",
    "Vehicle", "enu_from_geodetic", "geodetic_from_enu", "geodetic_from_ned", "mode_name", "ned_from_geodetic",
    "wrap_pi", "CameraHoverEnv", "HoverEnv", "Server", "Sim", "find_server",
]

__version__ = "0.1.0"

register_gymnasium()
