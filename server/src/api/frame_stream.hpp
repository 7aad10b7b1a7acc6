// The API's camera-frame subscriptions (docs/protocol.md "Camera frames"): camera_list, camera_subscribe,
// camera_unsubscribe, camera_blackout, and the frame messages (a JSON header line, then the raw image
// bytes; one such part per image of a capture: colour, depth, segmentation) with their back-pressure rules. An op group like the others, and a render::FrameConsumer:
// want() and the ops run on the loop thread, deliver() on the render thread.
#pragma once

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "api/line_server.hpp"
#include "api/op_table.hpp"
#include "render/frame_service.hpp"
#include "sim/simulation.hpp"

namespace uavsim::server::api {

// The most frames a subscription may skip between two it takes.
inline constexpr int kMaxFrameDivisor = 1000000;
// The n for which a subscriber takes every n-th frame of a camera rendering camera_fps_hz, so that
// it gets fps_hz frames a second: camera_fps_hz / n == fps_hz (within one part in a million), n in
// [1, kMaxFrameDivisor]; nullopt for any other fps (not finite, <= 0, between two such rates). The
// camera_subscribe op's rule, and --render-cameras'.
std::optional<int> frame_divisor(double camera_fps_hz, double fps_hz);

class FrameStream : public OpGroup, public render::FrameConsumer {
 public:
  // is_lockstep(conn): whether a connection has joined lockstep (its frames are never dropped). Loop
  // thread. sim (for the sim time of a blackout), service and server must outlive this object.
  FrameStream(const sim::Simulation& sim, render::FrameService& service, LineServer& server,
              std::function<bool(uint64_t)> is_lockstep);

  // The camera ops, served by this stream.
  void register_ops(OpTable& table) override;
  // The camera ops of a server that renders no frames: each answers not_available.
  static void register_unavailable(OpTable& table);
  // A tick is due for conn: the frames due at it reach the client before the tick (docs/protocol.md).
  void before_tick(uint64_t conn, const Send& send) override;
  // A subscriber's frames of the current step were captured before the API ran (and may have been
  // dropped as a free-running subscriber's): it joins lockstep at the next tick, not at this one.
  bool prepared_before_join(uint64_t conn) const override { return has_subscriptions(conn); }
  // A reset ends every blackout: their times were on the old clock.
  void on_reset() override { clear_blackouts(); }
  void on_disconnect(uint64_t conn) override;  // Loop thread.

  // The camera ops (camera_list, camera_subscribe, camera_unsubscribe, camera_blackout), each answering
  // in *reply. Loop thread.
  void op_list(const Json& request, OpReply* reply) const;
  void op_subscribe(uint64_t conn, const Json& request, OpReply* reply);
  void op_unsubscribe(uint64_t conn, const Json& request, OpReply* reply);
  // camera_blackout {camera, duration_s}: the camera's frames with a stamp in [now, now + duration) are
  // black (a blinded or failed sensor: frames keep coming, showing nothing); 0 ends a blackout.
  void op_blackout(const Json& request, OpReply* reply);
  // Ends every blackout (a reset: sim time restarts). Loop thread.
  void clear_blackouts();
  bool has_subscriptions(uint64_t conn) const;      // Loop thread.

  void want(int camera, int64_t index, int64_t stamp_us, std::vector<render::EncodingKey>* encodings,
            bool* must_deliver) override;
  void dropped(int camera, int64_t index) override;
  void deliver(const render::ReadyFrame& frame) override;

 private:
  struct Sub {
    uint64_t conn = 0;
    int camera = -1;
    std::vector<render::EncodingKey> keys;  // the images of each capture, in Encoding order (one part each)
    int every = 1;
    uint64_t next_seq = 0;               // loop thread
    std::atomic<bool> active{true};
    std::atomic<uint64_t> delivered{0};
    std::atomic<uint64_t> dropped{0};
  };
  struct Pending {
    std::shared_ptr<Sub> sub;
    uint64_t seq = 0;
    bool must = false;
  };
  Json camera_json(int index) const;
  // camera_subscribe's images: "format" or "modalities", "quality", checked against what the camera gives
  // and the size of a capture. Loop thread. Returns false with reply failed for an error reply.
  bool parse_keys(const Json& request, const render::FrameCamera& info, std::vector<render::EncodingKey>* keys,
                  OpReply* reply) const;
  // the request's "camera" (a name of camera_list), or nullopt with reply failed
  std::optional<int> camera_field(const Json& request, OpReply* reply) const;
  // camera_subscribe's reply for the depth and segmentation parts: the clip planes and field conditions,
  // the class and object tables
  Json depth_json(const render::FrameCamera& info) const;
  Json segmentation_json() const;

  const sim::Simulation& sim_;
  render::FrameService& service_;
  LineServer& server_;
  std::function<bool(uint64_t)> is_lockstep_;
  std::map<uint64_t, std::map<int, std::shared_ptr<Sub>>> subs_;  // conn -> camera -> sub; loop thread

  std::mutex mutex_;
  std::map<std::pair<int, int64_t>, std::vector<Pending>> pending_;  // (camera, frame) -> takers
  std::map<int, std::pair<int64_t, int64_t>> blackouts_;  // camera -> [from, until) stamp_us, guarded by mutex_
};

}  // namespace uavsim::server::api
