"""Depth and segmentation as numpy arrays: views of the C++ frame's planes, checked against the scene's
geometry (a quad hovering with a camera straight down over a balloon, and a level camera that sees sky),
and the modalities a subscription asks for checked before anything is sent."""

import math
import os

import numpy as np
import pytest

import uavsim
from uavsim import _core

from conftest import TESTS_DIR

WORLD = os.path.join(TESTS_DIR, "data", "rgbd_hover.xml")
HOVER_ALT_M = 6.0
GIMBAL_BELOW_BODY_M = 0.09  # the world's uavsim:gimbal offset: the camera under the body's origin
BALLOON_CENTRE_ENU_M = np.array([1.2, 0.0, 2.7])  # pole foot (1.2, 0, 0) + the sphere's 2.7 m
BALLOON_RADIUS_M = 0.3
LEVEL_CAMERA_HEIGHT_M = 2.0
# the depth buffer's resolution at 6 m with near 0.08 m (24 bits): z^2 / (near 2^24) ~ 3e-5 m; the rest
# is the four pixels around the principal point seeing the ground a little off the axis (< 1 mm here)
DEPTH_TOL_M = 0.01
# telemetry against the camera: the vehicle's tilt while hovering moves the gimbal's mount point
HOVER_TOL_M = 0.05
ALL = ["rgb", "depth", "segmentation"]


@pytest.fixture(scope="module")
def hover():
    with uavsim.Server(WORLD, seed=1) as s:
        uav = s.vehicle("uav0")
        uav.set_mode(uavsim.FlightMode.GUIDED)
        uav.arm()
        uav.takeoff(HOVER_ALT_M)
        s.run_for(1.0)  # settle
        yield s


def latest(server, camera):
    server.loop.run_until(lambda: camera.latest is not None, 5.0, "a frame")
    return camera.latest


def to_camera(frame, p_enu):
    """A world point in the frame's camera frame (x right, y down, z along the optical axis)."""
    return frame.pose.R_enu_cam.T @ (np.asarray(p_enu) - frame.pose.position_enu_m)


def test_planes_are_numpy_views_of_the_cpp_planes_byte_for_byte(hover):
    shots = _core._testing.capture_planes(hover.loop, "down", 3, ALL)
    assert len(shots) == 3
    for refs, f in shots:
        assert sorted(refs) == ["class_ids", "depth_m", "image", "object_ids"]
        assert f.image.shape == (60, 80, 3) and f.image.dtype == np.uint8
        assert f.depth_m.shape == (60, 80) and f.depth_m.dtype == np.float32
        assert f.object_ids.shape == (60, 80) and f.object_ids.dtype == np.uint16
        assert f.class_ids.shape == (60, 80) and f.class_ids.dtype == np.uint16
        for name in refs:
            a = getattr(f, name)
            assert a.tobytes() == refs[name], name
            assert not a.flags.owndata and a.base is not None, name  # a view over the frame's buffer
            assert a.flags.c_contiguous, name
    # the arrays stay valid after the subscription and its frames are gone on the C++ side
    assert shots[0][1].depth_m.tobytes() == shots[0][0]["depth_m"]
    assert shots[0][1].class_ids.tobytes() == shots[0][0]["class_ids"]
    # one capture: the planes of consecutive frames follow each other's seq
    assert [f.seq for _, f in shots] == list(range(shots[0][1].seq, shots[0][1].seq + 3))


def test_depth_at_the_image_centre_is_the_hover_height(hover):
    cam = hover.camera("down", modalities=ALL)
    assert 0 < cam.depth_near_m < 1.0 < HOVER_ALT_M < cam.depth_far_m
    f = latest(hover, cam)
    h, w = f.depth_m.shape
    k = f.intrinsics
    assert (k.cx, k.cy) == (pytest.approx((w - 1) / 2), pytest.approx((h - 1) / 2))
    # the ray through the principal point is the optical axis (R's third column): it meets the ground
    # (z = 0) after t = -c_z / axis_z, and its depth (along the axis) is t itself
    c, axis = f.pose.position_enu_m, f.pose.R_enu_cam[:, 2]
    assert axis[2] < -0.99  # the gimbal holds the camera straight down
    expected_m = -c[2] / axis[2]
    centre = f.depth_m[h // 2 - 1:h // 2 + 1, w // 2 - 1:w // 2 + 1]  # the 4 pixels around (cx, cy)
    assert np.all(np.isfinite(centre))
    assert float(centre.mean()) == pytest.approx(expected_m, abs=DEPTH_TOL_M)
    # and against the vehicle: hovering at the take-off altitude, the camera 0.09 m under its body
    body_z = hover.sim.vehicle("uav0")["position_enu_m"][2]
    assert body_z == pytest.approx(HOVER_ALT_M, abs=0.3)
    assert float(centre.mean()) == pytest.approx(body_z - GIMBAL_BELOW_BODY_M, abs=HOVER_TOL_M)
    cam.close()


def test_segmentation_labels_the_balloon_where_it_projects(hover):
    cam = hover.camera("down", modalities=["depth", "segmentation"])
    classes, objects = cam.segmentation_classes, cam.segmentation_objects
    assert classes[0] == "none" and {"ground", "vehicle", "balloon", "pole"} <= set(classes)
    assert [o.id for o in objects] == list(range(len(objects)))  # the list index is the id
    by_name = {o.name: o for o in objects}
    balloon, ground = by_name["b0"], by_name["ground"]
    assert classes[balloon.class_id] == "balloon" and classes[ground.class_id] == "ground"
    assert classes[by_name["b0/pole"].class_id] == "pole" and classes[by_name["uav0"].class_id] == "vehicle"

    f = latest(hover, cam)
    assert f.image is None  # no colour asked for
    # the balloon's centre through the camera model, and its apparent radius asin(r / d) in pixels
    p = to_camera(f, BALLOON_CENTRE_ENU_M)
    k = f.intrinsics
    u, v = k.fx * p[0] / p[2] + k.cx, k.fy * p[1] / p[2] + k.cy
    d = float(np.linalg.norm(p))
    r_px = k.fy * math.tan(math.asin(BALLOON_RADIUS_M / d))
    assert r_px > 3  # big enough to tell inside from outside
    h, w = f.class_ids.shape
    assert 0 <= u < w and 0 <= v < h
    vv, uu = np.mgrid[0:h, 0:w]
    dist_px = np.hypot(uu - u, vv - v)
    # off the axis the sphere projects to a slightly longer ellipse: margins of 20 % and a pixel
    inside = dist_px <= 0.8 * r_px - 0.5
    outside = dist_px >= 1.2 * r_px + 1.0
    assert inside.sum() >= 9
    assert np.all(f.class_ids[inside] == balloon.class_id)
    assert np.all(f.object_ids[inside] == balloon.id)
    assert not np.any(f.object_ids[outside] == balloon.id)
    assert np.all(f.class_ids[~inside & ~outside] != classes.index("marker"))
    # its nearest surface point on the ray through its centre: (d - r) along the ray, z of that
    iu, iv = int(round(u)), int(round(v))
    assert f.depth_m[iv, iu] == pytest.approx((d - BALLOON_RADIUS_M) * p[2] / d, abs=0.05)
    # the ground around it, object and class
    assert f.object_ids[0, 0] == ground.id and f.class_ids[h - 1, w - 1] == ground.class_id
    # the same ids in a later frame and a new subscription
    hover.run_for(0.5)
    g = cam.latest
    assert g.seq > f.seq and g.object_ids[iv, iu] == balloon.id
    cam.close()
    again = hover.camera("down", modalities=["segmentation"])
    assert [(o.id, o.name, o.class_id) for o in again.segmentation_objects] == [
        (o.id, o.name, o.class_id) for o in objects]
    again.close()


def test_nothing_hit_is_nan_depth_and_id_zero(hover):
    cam = hover.camera("level", modalities=["depth", "segmentation"])
    f = latest(hover, cam)
    assert f.image is None
    h, w = f.depth_m.shape
    k = f.intrinsics
    # the top row is sky (22.5 deg up: 10 m high at the balloon's 20 m, above the balloon and the
    # hovering quad): NaN and id 0 / class 0; NaN is exactly where nothing was hit, most of the upper half
    assert np.all(np.isnan(f.depth_m[0]))
    assert np.all(f.object_ids[0] == 0) and np.all(f.class_ids[0] == 0)
    np.testing.assert_array_equal(np.isnan(f.depth_m), f.class_ids == 0)
    np.testing.assert_array_equal(f.class_ids == 0, f.object_ids == 0)
    assert np.isnan(f.depth_m[: h // 2]).mean() > 0.9
    # the bottom row sees the ground: a ray (v - cy) / fy down from the level axis meets it at depth
    # z = height fy / (v - cy)
    expected_m = LEVEL_CAMERA_HEIGHT_M * k.fy / (h - 1 - k.cy)
    np.testing.assert_allclose(f.depth_m[h - 1], expected_m, rtol=0.002)
    assert np.all(f.class_ids[h - 1] == cam.segmentation_classes.index("ground"))
    cam.close()


def test_modalities_are_checked_before_subscribing(hover):
    for bad, words in ((["thermal"], "unknown modality 'thermal'"), ([], "1-5"),
                       (["rgb", "grey"], "one of rgb, grey, jpeg"), (["depth", "depth"], "twice"),
                       (["rgb", "depth", "segmentation", "grey", "jpeg", "depth"], "1-5")):
        with pytest.raises(uavsim.InvalidArgumentError) as e:
            hover.camera("down", modalities=bad)
        assert words in str(e.value), bad
    with pytest.raises(uavsim.InvalidArgumentError, match="not both"):
        hover.camera("down", format=uavsim.CameraFormat.BGR, modalities=["depth"])
    with pytest.raises(TypeError):
        hover.camera("down", modalities="depth")  # a list of names, not one string
    # a camera that does not give depth: the simulator refuses, naming what it gives
    with pytest.raises(uavsim.UavsimError) as e:
        hover.camera("plain", modalities=["rgb", "depth"])
    assert e.value.code == uavsim.Error.DENIED and "depth" in str(e.value)
    # the colour formats still work alone, and a colour-only frame has no planes
    cam = hover.camera("plain", modalities=["grey"])
    f = latest(hover, cam)
    assert f.image.shape == (48, 64) and f.depth_m is None and f.object_ids is None
    cam.close()
