// Helpers for vision tests on rendered frames: a shipped world with its objects, one offscreen
// renderer on it, and conversions from the renderer's frame to the vision library's types.
#pragma once

#include <gtest/gtest.h>
#include <mujoco/mujoco.h>

#include <Eigen/Geometry>
#include <cstdio>
#include <memory>
#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "objects/world_objects.hpp"
#include "physics/object_bodies.hpp"
#include "physics/world.hpp"
#include "render/camera_renderer.hpp"
#include "sim/simulation.hpp"
#include "uavsim/vision/camera_model.hpp"

namespace uavsim::vision::rendered {

namespace render = server::render;

// A shipped world (models/worlds/NAME) with its objects (truck, balloons, gimbals) and a renderer
// serving the given cameras. Construct and use on one thread (the renderer's).
struct RenderedWorld {
  std::unique_ptr<server::sim::Simulation> sim;
  server::objects::ObjectSet objects;
  std::unique_ptr<render::CameraRenderer> renderer;

  RenderedWorld(const std::string& world, uint64_t seed,
                std::vector<render::CameraConfig> cameras) {
    server::physics::ComposeOptions o;
    o.models_dir = UAVSIM_MODELS_DIR;
    server::sim::SimConfig c;
    c.seed = seed;
    sim = std::make_unique<server::sim::Simulation>(
        server::physics::World::load(std::string(UAVSIM_MODELS_DIR) + "/worlds/" + world, o), c);
    objects = server::objects::add_world_objects(*sim);
    renderer = std::make_unique<render::CameraRenderer>(sim->world().model(), std::move(cameras));
  }

  server::physics::World& world() { return sim->world(); }
  int body(const std::string& name) {
    const int id = world().body_id(name);
    EXPECT_GE(id, 0) << name;
    return id;
  }

  // kinematics for what was placed (mocap poses, qpos), as the renderer requires
  void forward() { mj_forward(world().model(), world().data()); }

  // places a mocap body whose x axis is the optical axis of the camera it holds (a gimbal body)
  void place_camera(const std::string& gimbal_body, const Eigen::Vector3d& position_enu_m,
                    const Eigen::Quaterniond& q_enu_gimbal) {
    ASSERT_TRUE(
        server::physics::set_mocap_pose(world(), body(gimbal_body), position_enu_m, q_enu_gimbal));
  }

  // MuJoCo's id of a geom by its full name ("b0/balloon"); fails the test if there is none
  int geom(const std::string& name) {
    const int id = mj_name2id(world().model(), mjOBJ_GEOM, name.c_str());
    EXPECT_GE(id, 0) << name;
    return id;
  }

  // the geom that the ray from a camera at `from` towards `to` meets first, or -1: every visible
  // geom counts, beyond the renderer's near clipping distance (what is nearer does not show)
  int first_hit(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
    const mjModel* m = world().model();
    const Eigen::Vector3d dir = (to - from).normalized();
    const Eigen::Vector3d start = from + m->vis.map.znear * m->stat.extent * dir;
    int id = -1;
    mj_ray(m, world().data(), start.data(), dir.data(), nullptr, 1, -1, &id);
    return id;
  }

  // renders camera `index` of the renderer after forward()
  render::CameraFrame render(int index = 0) {
    forward();
    render::CameraFrame f;
    renderer->render(world().data(), index, &f);
    return f;
  }
};

// Orientation of a gimbal body looking along azimuth yaw (ENU, from east counter-clockwise) and
// elevation pitch (up positive), image top up; the camera's xyaxes="0 -1 0 0 0 1" looks along +x.
inline Eigen::Quaterniond look(double yaw_rad, double pitch_rad) {
  return Eigen::Quaterniond(Eigen::AngleAxisd(yaw_rad, Eigen::Vector3d::UnitZ()) *
                            Eigen::AngleAxisd(-pitch_rad, Eigen::Vector3d::UnitY()));
}

// A gimbal orientation whose optical axis points from `from` to `to`.
inline Eigen::Quaterniond look_at(const Eigen::Vector3d& from, const Eigen::Vector3d& to) {
  const Eigen::Vector3d d = to - from;
  return look(std::atan2(d.y(), d.x()), std::atan2(d.z(), d.head<2>().norm()));
}

// The frame as an OpenCV BGR image (a copy; the renderer's rows are top first, like OpenCV's).
inline cv::Mat to_bgr(const render::CameraFrame& f) {
  const cv::Mat rgb(f.height_px, f.width_px, CV_8UC3, const_cast<uint8_t*>(f.pixels.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  return bgr;
}

inline CameraPose to_pose(const render::CameraFrame& f) {
  CameraPose p;
  p.position_enu_m = f.position_enu_m;
  p.R_enu_cam = f.R_enu_cam;
  return p;
}

// The full name of a part of balloon instance i of mbzirc2020.xml ("b3/balloon", "b3/pole").
inline std::string balloon_part(int i, const char* part) {
  char name[32];
  std::snprintf(name, sizeof(name), "b%d/%s", i, part);
  return name;
}

inline render::CameraConfig camera(const std::string& name, int width_px, int height_px) {
  render::CameraConfig c;
  c.camera = name;
  c.width_px = width_px;
  c.height_px = height_px;
  return c;
}

}  // namespace uavsim::vision::rendered
