#include "mavlink/mission_upload.hpp"

#include "uavsim/common/mavlink/generated/enums.hpp"

namespace uavsim::server::mavlink {

namespace {
using ::uavsim::common::mavlink::MavMissionResult;
using ::uavsim::common::mavlink::to_underlying;
constexpr std::uint8_t result(MavMissionResult r) {
  return static_cast<std::uint8_t>(to_underlying(r));
}
}  // namespace

const std::uint8_t MissionUpload::kInvalidSequence = result(MavMissionResult::InvalidSequence);

UploadStep MissionUpload::on_count(int count, int mission_type, double now_s) {
  UploadStep step;
  if (mission_type != kMissionTypeMission) {  // no fence or rally support
    step.ack = result(MavMissionResult::Unsupported);
    step.ack_mission_type = static_cast<std::uint8_t>(mission_type);
    return step;
  }
  if (count > kMaxItems) {
    step.ack = result(MavMissionResult::NoSpace);
    return step;
  }
  reset();
  if (count == 0) {  // an empty upload clears the mission
    step.mission.emplace();
    step.ack = result(MavMissionResult::Accepted);
    return step;
  }
  active_ = true;
  count_ = count;
  next_seq_ = 0;
  last_activity_s_ = now_s;
  items_.reserve(static_cast<std::size_t>(count));
  return request(now_s);
}

UploadStep MissionUpload::take(fc::MissionItem item, double now_s) {
  items_.push_back(std::move(item));
  ++next_seq_;
  if (next_seq_ < count_) return request(now_s);
  // complete: the mission goes to the flight controller
  UploadStep step;
  step.mission = std::move(items_);
  reset();
  step.ack = result(MavMissionResult::Accepted);
  return step;
}

UploadStep MissionUpload::request(double now_s) {
  last_request_s_ = now_s;
  UploadStep step;
  step.request_seq = next_seq_;
  return step;
}

UploadStep MissionUpload::on_unreadable_item() {
  // an item that cannot even be read ends an upload in progress, as a bad item does
  if (active_) reset();
  UploadStep step;
  step.ack = result(MavMissionResult::Error);
  return step;
}

UploadStep MissionUpload::on_tick(double now_s) {
  if (!active_) return {};
  if (now_s - last_activity_s_ > kTimeoutS) {
    reset();
    UploadStep step;
    step.ack = result(MavMissionResult::OperationCancelled);
    return step;
  }
  if (now_s - last_request_s_ >= kRequestRetryS) return request(now_s);
  return {};
}

}  // namespace uavsim::server::mavlink
