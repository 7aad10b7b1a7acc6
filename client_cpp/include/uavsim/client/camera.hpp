// CameraSubscriber: camera frames as cv::Mat with their sim timestamp, pinhole intrinsics and camera pose,
// from the simulator's frame protocol (docs/protocol.md "Camera frames").
//
// The frames arrive one way on either clock, as `frame` messages on a simulator connection; the clock
// decides only their pacing. Under a lockstep loop that is the loop's own connection, read at ticks, so
// every frame due at or before a tick has been handed to on_frame before that tick's timers run (none is
// ever dropped). On the host clock it is a connection of the subscriber's own to the simulator's API
// (CameraConfig::api_address, else UAVSIM_API=host:port, else 127.0.0.1:5700), read as bytes arrive;
// frames may then be dropped when the reader is slow (counted).
// On a real drone the frames come from the camera driver instead (seed 6.1): the same CameraFrame type is
// what image-processing code should take.
//
// Loop-thread only, like everything on an EventLoop.
#pragma once

#include <cstdint>
#include <functional>
#include <memory>
#include <string>

#include <Eigen/Core>
#include <opencv2/core.hpp>

#include "uavsim/client/event_loop.hpp"
#include "uavsim/client/result.hpp"

namespace uavsim::client {

// OpenCV pinhole convention, no distortion: u = fx X/Z + cx, v = fy Y/Z + cy (camera x right, y down, z forward).
struct CameraIntrinsics {
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  cv::Matx33d matrix() const { return {fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0}; }
};

struct CameraPose {
  Eigen::Vector3d position_enu_m = Eigen::Vector3d::Zero();  // optical centre
  Eigen::Matrix3d R_enu_cam = Eigen::Matrix3d::Identity();   // camera frame -> ENU; column 2 = optical axis
};

struct CameraFrame {
  std::string camera;
  std::string vehicle;        // owning vehicle's name; empty for a world camera
  std::int64_t seq = 0;       // due frames since subscribing (a gap is a lost frame)
  std::int64_t dropped = 0;   // frames of this subscription dropped so far
  double stamp_s = 0.0;       // sim time the image shows
  std::int64_t stamp_us = 0;
  cv::Mat image;              // CV_8UC3 BGR (OpenCV's order) or CV_8UC1 grey
  CameraIntrinsics intrinsics;
  CameraPose pose;
};

enum class CameraFormat {
  kBgr,   // raw RGB on the wire, handed over as BGR
  kGrey,  // raw 8-bit luma
  kJpeg,  // JPEG on the wire (smaller), decoded to BGR
};

struct CameraConfig {
  std::string camera;          // the camera's name in the world (e.g. "uav0_front")
  CameraFormat format = CameraFormat::kBgr;
  double fps = 0.0;            // 0: the camera's rate; else that rate divided by a whole number
  int jpeg_quality = 90;
  std::string api_address;     // host clock only: "host:port" of the simulator API
};

class CameraSubscriber {
 public:
  // Subscribes and waits for the simulator's answer (timeout_s on the loop clock, wall seconds for the
  // connection on the host clock). kDenied with the simulator's message for an unknown camera, a bad fps or
  // a server without cameras.
  static Result<std::unique_ptr<CameraSubscriber>> subscribe(EventLoop& loop, const CameraConfig& config,
                                                             std::function<void(const CameraFrame&)> on_frame,
                                                             double timeout_s = 10.0);
  ~CameraSubscriber();  // unsubscribes
  CameraSubscriber(const CameraSubscriber&) = delete;
  CameraSubscriber& operator=(const CameraSubscriber&) = delete;

  int width() const;
  int height() const;
  double fps() const;
  CameraIntrinsics intrinsics() const;
  std::uint64_t frames_received() const;
  std::int64_t frames_dropped() const;  // as the simulator counts them
  bool connected() const;

 private:
  struct Impl;
  explicit CameraSubscriber(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::client
