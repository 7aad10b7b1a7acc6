"""Camera frames as numpy arrays: the same bytes the C++ library holds, without a copy, with their sim
stamps, intrinsics and pose."""

import numpy as np
import pytest

import uavsim
from uavsim import _core

W, H = 64, 48


def test_frames_are_numpy_views_of_the_cpp_frames_byte_for_byte(empty_world):
    # the C++ subscriber alone, with a byte copy of each cv::Mat taken in C++ beside the binding's Frame
    shots = _core._testing.capture_frames(empty_world.loop, "overview", 4)
    assert len(shots) == 4
    for ref, frame in shots:
        img = frame.image
        assert img.shape == (H, W, 3) and img.dtype == np.uint8
        assert img.tobytes() == ref
        assert not img.flags.owndata and img.base is not None  # a view over the frame's buffer
        assert img.flags.c_contiguous
    # the arrays stay valid after the subscription and its frames are gone on the C++ side
    assert shots[0][1].image.tobytes() == shots[0][0]
    # not a blank picture: the ground and the sky differ
    assert shots[-1][1].image.std() > 1.0
    grey = _core._testing.capture_frames(empty_world.loop, "overview", 2, uavsim.CameraFormat.GREY)
    for ref, frame in grey:
        assert frame.image.shape == (H, W) and frame.image.tobytes() == ref


def test_camera_subscription_under_lockstep(empty_world):
    got = []
    cam = empty_world.camera("overview", on_frame=got.append, queue=4)
    assert (cam.width, cam.height) == (W, H) and cam.fps == pytest.approx(10.0)
    k = cam.intrinsics
    assert k.fx > 0 and k.cx == pytest.approx(W / 2, abs=1) and k.cy == pytest.approx(H / 2, abs=1)
    np.testing.assert_allclose(k.matrix(), [[k.fx, 0, k.cx], [0, k.fy, k.cy], [0, 0, 1]])
    empty_world.run_for(1.0)
    assert len(got) >= 9
    f = cam.latest
    assert f is got[-1] and f.camera == "overview" and f.vehicle == ""
    # frames due at or before a tick arrive before it: the latest frame is at most one period old
    assert 0 <= empty_world.now() - f.stamp_s <= 0.1 + 1e-9
    assert f.stamp_us == round(f.stamp_s * 1e6)
    stamps = [g.stamp_s for g in got]
    assert stamps == sorted(stamps) and [g.seq for g in got] == list(range(got[0].seq, got[0].seq + len(got)))
    np.testing.assert_allclose(f.pose.position_enu_m, [-12, -12, 8], atol=1e-6)
    R = f.pose.R_enu_cam
    np.testing.assert_allclose(R.T @ R, np.eye(3), atol=1e-9)
    queued = cam.take_frames()
    assert len(queued) == 4 and queued[-1] is f and cam.frames_overflowed == len(got) - 4
    assert cam.take_frames() == []
    assert cam.frames_received == len(got) and cam.frames_dropped == 0
    cam.close()
    with pytest.raises(uavsim.ConnectionError):
        cam.width


def test_camera_errors(empty_world):
    with pytest.raises(uavsim.UavsimError) as e:
        empty_world.camera("no_such_camera")
    assert e.value.code == uavsim.Error.DENIED
    with pytest.raises(uavsim.InvalidArgumentError):
        empty_world.camera("overview", fps=-1.0)
    with pytest.raises(uavsim.InvalidArgumentError):
        empty_world.camera("overview", format=uavsim.CameraFormat.JPEG, jpeg_quality=0)
    with pytest.raises(TypeError):
        empty_world.camera("overview", format="bgr")


def test_camera_on_the_host_clock():
    with uavsim.Server("empty", seed=1, cameras={"overview": "width=32,height=24,fps=20"}, lockstep=False) as s:
        cam = s.camera("overview", format=uavsim.CameraFormat.JPEG)
        s.loop.run_until(lambda: cam.latest is not None, 30.0, "a frame")
        assert cam.latest.image.shape == (24, 32, 3)
