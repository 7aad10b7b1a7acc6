// RadioLink over the simulator's radio (uavsim::client::A2aRadio).
#include "radio_link.hpp"
#include "uavsim/client/radio.hpp"

namespace uavsim::missions::coverage {

namespace {

class SimRadioLink : public RadioLink {
 public:
  explicit SimRadioLink(std::unique_ptr<client::A2aRadio> radio) : radio_(std::move(radio)) {}
  bool broadcast(const Frame& frame) override { return radio_->send(frame).ok(); }
  size_t max_frame_bytes() const override { return radio_->max_frame_bytes(); }
  std::vector<Frame> take_received() override {
    std::vector<client::RadioFrame> heard = radio_->take_received();
    std::vector<Frame> out;
    out.reserve(heard.size());  // tens of frames a step: one allocation, not one per doubling
    for (client::RadioFrame& f : heard) out.push_back(std::move(f.data));
    return out;
  }
  unsigned long refused() const override { return radio_->counters().refused; }

 private:
  std::unique_ptr<client::A2aRadio> radio_;
};

}  // namespace

std::unique_ptr<RadioLink> open_sim_radio(client::EventLoop& loop, int index, std::string* error) {
  auto r = client::A2aRadio::open(loop, index);
  if (!r) {
    if (error) *error = r.message();
    return nullptr;
  }
  return std::make_unique<SimRadioLink>(std::move(r.value()));
}

}  // namespace uavsim::missions::coverage
