// CameraSubscriber: camera frames as cv::Mat with their sim timestamp, pinhole intrinsics and camera pose,
// and where the camera gives them depth and segmentation of the same capture, from the simulator's frame
// protocol (docs/protocol.md "Camera frames").
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
#include <vector>

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
  cv::Mat image;              // CV_8UC3 BGR (OpenCV's order) or CV_8UC1 grey; empty without colour
  CameraIntrinsics intrinsics;
  CameraPose pose;
  // Depth and segmentation (CameraConfig::depth, ::segmentation) of the same capture as the image: the
  // same instant, pose, stamp and seq. Empty when not asked for.
  cv::Mat depth_m;     // CV_32FC1, metres along the optical axis (camera z), NaN where nothing was measured
  cv::Mat object_ids;  // CV_16UC1, 0 where nothing was hit (CameraSubscriber::segmentation_objects())
  cv::Mat class_ids;   // CV_16UC1, 0 where nothing was hit (CameraSubscriber::segmentation_classes())
};

// An object of the segmentation images: its id in CameraFrame::object_ids, its name in the world ("uav0",
// "b0", "b0/pole", "truck/marker", ...) and its class id.
struct SegmentationObject {
  int id = 0;
  std::string name;
  int class_id = 0;
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
  // what else each frame carries, if the camera gives it (the world's or --camera's modalities=): depth
  // and segmentation, rendered only for subscribers that ask; colour = false leaves the image out
  bool colour = true;
  bool depth = false;
  bool segmentation = false;
};

class CameraSubscriber {
 public:
  // Subscribes and waits for the simulator's answer (timeout_s on the loop clock, wall seconds for the
  // connection on the host clock). kDenied with the simulator's message for an unknown camera, a bad fps,
  // a modality the camera does not give, or a server without cameras; kInvalidArgument for a config that
  // asks for no image at all. on_frame gets each capture once all of its images have arrived.
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
  // The clip planes of the depth images, in metres (0 without depth): nothing nearer or farther is seen.
  double depth_near_m() const;
  double depth_far_m() const;
  // The segmentation's classes by id ("none", "ground", "vehicle", "balloon", ...) and objects (index =
  // id); empty without segmentation. Ids are the same in every frame and every run of a world.
  const std::vector<std::string>& segmentation_classes() const;
  const std::vector<SegmentationObject>& segmentation_objects() const;

 private:
  struct Impl;
  explicit CameraSubscriber(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace uavsim::client
