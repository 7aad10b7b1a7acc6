// SPDX-License-Identifier: GPL-2.0-only
// Copyright the uavsim authors.
//
// uavsim-ns3-radio: the ns3 backend of uavsim's A2A radio (IEEE 802.15.4, ns-3's lr-wpan: O-QPSK
// 250 kbit/s, unslotted CSMA-CA, ACK and retries for unicast, SINR error model), a separate program
// because ns-3 is GPL-2.0-only and uavsim-server is Apache-2.0 (README.md here). The server spawns
// it with one end of a socket pair (--fd N) and steps it in lockstep (wire.hpp): before each slice
// it pushes the vehicles' positions and velocities, the extra losses of blocked paths and the
// frames sent, then ns-3 runs to the step's time (Simulator::Stop(t - Now()) + Run()) and the
// receptions, confirms and counters of the slice go back.
//
// Determinism: RngSeedManager seed 1, run = the server's radio seed, set before any object exists;
// the devices' and loss models' streams pinned with AssignStreams; frames handed to the MACs in the
// order the server sends them ((sender, seq) of one step); integer nanosecond stop times.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <deque>
#include <map>
#include <memory>
#include <set>
#include <string>
#include <vector>

#include "ns3/constant-velocity-mobility-model.h"
#include "ns3/double.h"
#include "ns3/lr-wpan-csmaca.h"
#include "ns3/lr-wpan-mac.h"
#include "ns3/lr-wpan-net-device.h"
#include "ns3/lr-wpan-phy.h"
#include "ns3/mobility-helper.h"
#include "ns3/node-container.h"
#include "ns3/packet.h"
#include "ns3/pointer.h"
#include "ns3/propagation-delay-model.h"
#include "ns3/propagation-loss-model.h"
#include "ns3/random-variable-stream.h"
#include "ns3/rng-seed-manager.h"
#include "ns3/simulator.h"
#include "ns3/single-model-spectrum-channel.h"
#include "uavsim_ns3_parts.h"
#include "wire.hpp"

namespace {

using namespace ns3;
namespace wire = uavsim::ns3wire;
using uavsim_ns3::address;
using uavsim_ns3::Frame;
using uavsim_ns3::index_of;
using uavsim_ns3::quiet_until_ns;
using uavsim_ns3::UavsimLinkLoss;

constexpr uint16_t kPanId = 1;
// 802.15.4 data frame with short addresses and a compressed PAN id: frame control 2, sequence 1,
// destination PAN 2, destination 2, source 2, FCS 2
constexpr uint32_t kMacHeaderBytes = 11;
constexpr uint32_t kMaxPayloadBytes = 127 - kMacHeaderBytes;
// a frame's receptions end a propagation delay after its sender's confirm (microseconds at radio
// ranges); counters are settled this long after the confirm
constexpr int64_t kSettle_ns = 100000;
// 802.15.4's default macMinBE (ns-3's too): the random backoff of unslotted CSMA-CA
constexpr uint8_t kStandardMacMinBE = 3;
// O-QPSK 250 kbit/s: 32 us a byte; the PHY's preamble, delimiter and length take 6 bytes
constexpr int64_t kByte_ns = 32000;
constexpr uint32_t kPhyHeaderBytes = 6;

class Helper {
 public:
  explicit Helper(int fd) : fd_(fd) {}

  int run() {
    std::vector<uint8_t> body;
    for (;;) {
      const wire::IoResult r = wire::read_message(fd_, -1, &body);
      if (r != wire::IoResult::kOk) {
        // the server went away: nothing to report to
        return r == wire::IoResult::kClosed ? 0 : 1;
      }
      wire::Reader in(body.data(), body.size());
      const auto type = static_cast<wire::MessageType>(in.get<uint8_t>());
      if (!in.ok()) return error("empty message");
      bool sent = false;
      switch (type) {
        case wire::MessageType::kInit: {
          const auto vehicles = in.get<uint32_t>();
          const auto seed = in.get<uint64_t>();
          const wire::Channel c = wire::get_channel(in);
          if (!in.ok() || vehicles == 0 || vehicles > wire::kMaxVehicles) {
            return error("malformed init");
          }
          vehicles_ = vehicles;
          channel_ = c;
          build(seed);
          sent = ready();
          break;
        }
        case wire::MessageType::kConfig: {
          const wire::Channel c = wire::get_channel(in);
          if (!in.ok() || vehicles_ == 0) return error("malformed config");
          channel_ = c;
          apply_channel();
          sent = ready();
          break;
        }
        case wire::MessageType::kReset: {
          const auto seed = in.get<uint64_t>();
          if (!in.ok() || vehicles_ == 0) return error("malformed reset");
          build(seed);
          sent = ready();
          break;
        }
        case wire::MessageType::kStep:
          if (vehicles_ == 0) return error("step before init");
          if (!step(in)) return error("malformed step");
          sent = step_done();
          break;
        case wire::MessageType::kQuit:
          Simulator::Destroy();
          return 0;
        default:
          return error("unknown message type " + std::to_string(static_cast<int>(type)));
      }
      if (!sent) return 1;
    }
  }

 private:
  int error(const std::string& what) {
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kError));
    const auto n = static_cast<uint16_t>(std::min<size_t>(what.size(), 4000));
    w.put(n);
    w.bytes(reinterpret_cast<const uint8_t*>(what.data()), n);
    wire::write_all(fd_, w.message());
    std::fprintf(stderr, "uavsim-ns3-radio: %s\n", what.c_str());
    return 2;
  }

  bool ready() {
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kReady));
    w.put(kMaxPayloadBytes);
    return wire::write_all(fd_, w.message()) == wire::IoResult::kOk;
  }

  // a fresh ns-3 world: one node per vehicle on one 802.15.4 channel (pitfall: one ns-3 world per
  // process, so a reset destroys the old one first and time restarts at 0)
  void build(uint64_t seed) {
    Simulator::Destroy();
    macs_.clear();
    csmas_.clear();
    mobility_.clear();
    frames_.clear();
    pending_.assign(vehicles_, {});
    deliveries_ = wire::Writer();
    confirms_ = wire::Writer();
    counters_ = wire::Writer();
    delivery_count_ = confirm_count_ = counter_count_ = 0;
    RngSeedManager::SetSeed(1);
    RngSeedManager::SetRun(seed);

    NodeContainer nodes;
    nodes.Create(vehicles_);
    MobilityHelper mobility;
    mobility.SetMobilityModel("ns3::ConstantVelocityMobilityModel");
    mobility.Install(nodes);

    channel_model_ = CreateObject<SingleModelSpectrumChannel>();
    log_distance_ = CreateObject<LogDistancePropagationLossModel>();
    log_distance_->SetAttribute("ReferenceDistance", DoubleValue(1.0));
    shadowing_ = CreateObject<RandomPropagationLossModel>();
    shadowing_variable_ = CreateObject<NormalRandomVariable>();
    shadowing_->SetAttribute("Variable", PointerValue(shadowing_variable_));
    link_loss_ = CreateObject<UavsimLinkLoss>();
    link_loss_->configure(channel_, vehicles_);
    log_distance_->SetNext(shadowing_);
    shadowing_->SetNext(link_loss_);
    channel_model_->AddPropagationLossModel(log_distance_);
    apply_channel();
    channel_model_->SetPropagationDelayModel(CreateObject<ConstantSpeedPropagationDelayModel>());

    // devices made by hand: LrWpanHelper::Install calls SetNode after Node::AddDevice already did,
    // and in 3.37 that second configuration leaves the channel delivering nothing (every unicast
    // ends in NO_ACK)
    int64_t stream = 0;
    for (uint32_t i = 0; i < vehicles_; ++i) {
      Ptr<LrWpanNetDevice> dev = CreateObject<LrWpanNetDevice>();
      dev->SetChannel(channel_model_);
      nodes.Get(i)->AddDevice(dev);
      Ptr<LrWpanMac> mac = dev->GetMac();
      mac->SetPanId(kPanId);
      mac->SetShortAddress(address(i));
      mac->SetMcpsDataIndicationCallback(MakeBoundCallback(&Helper::on_indication, this, i));
      mac->SetMcpsDataConfirmCallback(MakeBoundCallback(&Helper::on_confirm, this, i));
      dev->GetPhy()->TraceConnectWithoutContext("PhyTxBegin",
                                                MakeBoundCallback(&Helper::on_tx_begin, this, i));
      dev->GetPhy()->TraceConnectWithoutContext("PhyTxEnd",
                                                MakeBoundCallback(&Helper::on_tx_end, this, i));
      macs_.push_back(mac);
      csmas_.push_back(dev->GetCsmaCa());
      mobility_.push_back(nodes.Get(i)->GetObject<ConstantVelocityMobilityModel>());
      // the PHY's own mobility: without it the channel applies no loss and no delay
      dev->GetPhy()->SetMobility(mobility_.back());
      stream += dev->AssignStreams(stream);
    }
    shadowing_variable_->SetStream(stream);
    apply_mac();
  }

  // the loss chain, fixed: log-distance, shadowing, ours; with the range model (or no shadowing)
  // the first two are set to add nothing (exponent and reference loss 0, variance 0)
  void apply_channel() {
    link_loss_->set_channel(channel_);
    const bool log = channel_.log_distance != 0;
    log_distance_->SetAttribute("Exponent", DoubleValue(log ? channel_.path_loss_exponent : 0.0));
    log_distance_->SetAttribute("ReferenceLoss",
                                DoubleValue(log ? channel_.reference_loss_db : 0.0));
    const double sigma_db = log ? channel_.shadowing_sigma_db : 0.0;
    shadowing_variable_->SetAttribute("Mean", DoubleValue(0.0));
    shadowing_variable_->SetAttribute("Variance", DoubleValue(sigma_db * sigma_db));
    apply_mac();
  }

  void apply_mac() {
    // TDMA: the server hands each frame over at its sender's slot, which no other sender uses, so
    // the random backoff (up to 7 x 320 us with the standard's macMinBE 3) would only push the
    // frame towards the next slot; macMinBE 0 leaves one clear-channel assessment, which still
    // defers to a frame overrunning its slot (a unicast's retries)
    for (const Ptr<LrWpanCsmaCa>& csma : csmas_) {
      csma->SetMacMinBE(channel_.tdma ? 0 : kStandardMacMinBE);
    }
  }

  bool step(wire::Reader& in) {
    const auto t_ns = in.get<int64_t>();
    const auto with_kinematics = in.get<uint8_t>();
    if (!in.ok() || t_ns < Simulator::Now().GetNanoSeconds()) return false;
    // the slice: ns-3 runs to the step's time (one Stop event when nothing else is queued)
    if (t_ns > Simulator::Now().GetNanoSeconds()) {
      Simulator::Stop(NanoSeconds(t_ns) - Simulator::Now());
      Simulator::Run();
    }
    if (with_kinematics) {
      for (uint32_t i = 0; i < vehicles_; ++i) {
        double v[6];
        for (double& x : v) x = in.get<double>();
        if (!in.ok()) return false;
        mobility_[i]->SetPosition(Vector(v[0], v[1], v[2]));
        mobility_[i]->SetVelocity(Vector(v[3], v[4], v[5]));
      }
    }
    const auto losses = in.get<uint32_t>();
    if (!in.ok() || losses > in.left() / 16) return false;
    for (uint32_t k = 0; k < losses; ++k) {
      const auto from = in.get<uint32_t>();
      const auto to = in.get<uint32_t>();
      const auto db = in.get<double>();
      if (!in.ok() || from >= vehicles_ || to >= vehicles_ || !(db >= 0.0 && db <= 1000.0)) {
        return false;
      }
      link_loss_->set_extra(from, to, db);
    }
    const auto frames = in.get<uint32_t>();
    if (!in.ok() || frames > in.left() / 34) return false;
    for (uint32_t k = 0; k < frames; ++k) {
      Frame f;
      f.from = in.get<uint32_t>();
      f.to = in.get<int32_t>();
      f.seq = in.get<uint64_t>();
      f.queued_ns = in.get<int64_t>();
      const auto at_ns = in.get<int64_t>();
      const auto n = in.get<uint16_t>();
      std::vector<uint8_t> data;
      if (!in.ok() || f.from >= vehicles_ || f.to < -1 || f.to >= static_cast<int32_t>(vehicles_) ||
          f.to == static_cast<int32_t>(f.from) || n == 0 || n > kMaxPayloadBytes ||
          (at_ns != -1 && at_ns < t_ns) || !in.bytes(n, &data)) {
        return false;
      }
      hand(std::move(f), data, at_ns);
    }
    settle();
    return in.ok();
  }

  // a frame to its sender's MAC, now (at_ns -1) or at at_ns (its TDMA slot): broadcast, or unicast
  // with ACK and retries
  void hand(Frame f, const std::vector<uint8_t>& data, int64_t at_ns) {
    Ptr<Packet> p = Create<Packet>(data.data(), static_cast<uint32_t>(data.size()));
    McpsDataRequestParams params;
    params.m_srcAddrMode = SHORT_ADDR;
    params.m_dstAddrMode = SHORT_ADDR;
    params.m_dstPanId = kPanId;
    params.m_dstAddr =
        f.to < 0 ? Mac16Address::GetBroadcast() : address(static_cast<uint32_t>(f.to));
    params.m_msduHandle = static_cast<uint8_t>(f.seq & 0xff);
    params.m_txOptions = f.to < 0 ? TX_OPTION_NONE : TX_OPTION_ACK;
    f.received.assign(vehicles_, 0);
    f.rx_dbm.assign(vehicles_, -1000.0);
    f.request_ns = at_ns < 0 ? Simulator::Now().GetNanoSeconds() : at_ns;
    f.airtime_ns = static_cast<int64_t>(data.size() + kMacHeaderBytes + kPhyHeaderBytes) * kByte_ns;
    const uint32_t from = f.from;
    // in frames_ from now on: the helper stays busy until the frame is settled
    frames_.emplace(p->GetUid(), std::move(f));
    if (at_ns < 0) {
      request(this, from, params, p);
    } else {
      Simulator::Schedule(NanoSeconds(at_ns) - Simulator::Now(), &Helper::request, this, from,
                          params, p);
    }
  }

  static void request(Helper* h, uint32_t from, McpsDataRequestParams params, Ptr<Packet> p) {
    // the MAC confirms in the order of its requests
    h->pending_[from].push_back(p->GetUid());
    h->macs_[from]->McpsDataRequest(params, p);
  }

  void counter(uint32_t from, uint32_t to, wire::Counter c) {
    counters_.put(from);
    counters_.put(to);
    counters_.put(static_cast<uint8_t>(c));
    ++counter_count_;
  }

  static void on_tx_begin(Helper* h, uint32_t vehicle, Ptr<const Packet> p) {
    // the data frame's first time on air (ACKs and unknown packets are not ours to count)
    auto it = h->frames_.find(p->GetUid());
    if (it == h->frames_.end() || it->second.from != vehicle || it->second.tx_start_ns >= 0) return;
    Frame& f = it->second;
    f.tx_start_ns = Simulator::Now().GetNanoSeconds();
    h->counter(f.from, f.from, wire::Counter::kTransmitted);
    for (uint32_t r = 0; r < h->vehicles_; ++r) {
      if (r == f.from || (f.to >= 0 && static_cast<uint32_t>(f.to) != r)) continue;
      h->counter(f.from, r, wire::Counter::kSent);
    }
  }

  static void on_tx_end(Helper* h, uint32_t vehicle, Ptr<const Packet> p) {
    // the channel computed every receiver's power when this transmission started
    auto it = h->frames_.find(p->GetUid());
    if (it == h->frames_.end() || it->second.from != vehicle) return;
    for (uint32_t r = 0; r < h->vehicles_; ++r) {
      if (r != vehicle) it->second.rx_dbm[r] = h->link_loss_->last_dbm(vehicle, r);
    }
    if (it->second.tx_end_ns < 0) it->second.tx_end_ns = Simulator::Now().GetNanoSeconds();
  }

  static void on_indication(Helper* h, uint32_t vehicle, McpsDataIndicationParams params,
                            Ptr<Packet> p) {
    auto it = h->frames_.find(p->GetUid());
    if (it == h->frames_.end()) return;
    Frame& f = it->second;
    const int64_t from = index_of(params.m_srcAddr);
    if (from != static_cast<int64_t>(f.from) || f.received[vehicle]) return;  // a retry's copy
    f.received[vehicle] = 1;
    h->counter(f.from, vehicle, wire::Counter::kDelivered);
    std::vector<uint8_t> data(p->GetSize());
    p->CopyData(data.data(), static_cast<uint32_t>(data.size()));
    wire::Writer& w = h->deliveries_;
    w.put(vehicle);
    w.put(f.from);
    w.put(f.seq);
    w.put<uint8_t>(f.to < 0 ? 1 : 0);
    w.put(f.queued_ns);
    w.put(f.tx_start_ns);
    w.put(Simulator::Now().GetNanoSeconds());
    w.put(params.m_mpduLinkQuality);
    w.put(static_cast<uint16_t>(data.size()));
    w.bytes(data.data(), data.size());
    ++h->delivery_count_;
  }

  static void on_confirm(Helper* h, uint32_t vehicle, McpsDataConfirmParams params) {
    // a MAC confirms its requests in the order they were made
    if (h->pending_[vehicle].empty()) return;
    const uint64_t uid = h->pending_[vehicle].front();
    h->pending_[vehicle].pop_front();
    Frame& f = h->frames_.at(uid);
    f.confirmed_ns = Simulator::Now().GetNanoSeconds();
    wire::ConfirmStatus status = wire::ConfirmStatus::kOther;
    switch (params.m_status) {
      case IEEE_802_15_4_SUCCESS:
        status = wire::ConfirmStatus::kSuccess;
        break;
      case IEEE_802_15_4_CHANNEL_ACCESS_FAILURE:
        status = wire::ConfirmStatus::kChannelAccessFailure;
        h->counter(vehicle, vehicle, wire::Counter::kChannelAccessFailure);
        break;
      case IEEE_802_15_4_NO_ACK:
        status = wire::ConfirmStatus::kNoAck;
        h->counter(vehicle, static_cast<uint32_t>(f.to), wire::Counter::kNoAck);
        break;
      default:
        break;
    }
    h->confirms_.put(vehicle);
    h->confirms_.put(f.seq);
    h->confirms_.put(static_cast<uint8_t>(status));
    ++h->confirm_count_;
  }

  // frames confirmed long enough ago that every reception has ended: each intended receiver that
  // did not get a frame that went on air counts once, below sensitivity or lost (interference,
  // SINR errors, busy receiving or sending)
  void settle() {
    const int64_t now_ns = Simulator::Now().GetNanoSeconds();
    for (auto it = frames_.begin(); it != frames_.end();) {
      const Frame& f = it->second;
      if (f.confirmed_ns < 0 || now_ns < f.confirmed_ns + kSettle_ns) {
        ++it;
        continue;
      }
      if (f.tx_start_ns >= 0) {
        for (uint32_t r = 0; r < vehicles_; ++r) {
          if (r == f.from || f.received[r] || (f.to >= 0 && static_cast<uint32_t>(f.to) != r)) {
            continue;
          }
          const bool heard = f.rx_dbm[r] >= channel_.sensitivity_dbm;
          counter(f.from, r, heard ? wire::Counter::kLost : wire::Counter::kOutOfRange);
        }
      }
      it = frames_.erase(it);
    }
  }

  bool step_done() {
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kStepDone));
    w.put(Simulator::Now().GetNanoSeconds());
    w.put<uint8_t>(frames_.empty() ? 0 : 1);
    w.put(quiet_until_ns(frames_, Simulator::Now().GetNanoSeconds(), kSettle_ns));
    auto append = [&w](uint32_t count, const wire::Writer& part) {
      w.put(count);
      const std::vector<uint8_t> m = part.message();
      w.bytes(m.data() + 4, m.size() - 4);
    };
    append(delivery_count_, deliveries_);
    append(confirm_count_, confirms_);
    append(counter_count_, counters_);
    deliveries_ = wire::Writer();
    confirms_ = wire::Writer();
    counters_ = wire::Writer();
    delivery_count_ = confirm_count_ = counter_count_ = 0;
    return wire::write_all(fd_, w.message()) == wire::IoResult::kOk;
  }

  int fd_;
  uint32_t vehicles_ = 0;
  wire::Channel channel_;
  Ptr<SingleModelSpectrumChannel> channel_model_;
  Ptr<LogDistancePropagationLossModel> log_distance_;
  Ptr<RandomPropagationLossModel> shadowing_;
  Ptr<NormalRandomVariable> shadowing_variable_;
  Ptr<UavsimLinkLoss> link_loss_;
  std::vector<Ptr<LrWpanMac>> macs_;
  std::vector<Ptr<LrWpanCsmaCa>> csmas_;
  std::vector<Ptr<ConstantVelocityMobilityModel>> mobility_;
  std::map<uint64_t, Frame> frames_;               // by packet uid, until settled
  std::vector<std::deque<uint64_t>> pending_;      // per sender: uids awaiting their confirm
  wire::Writer deliveries_, confirms_, counters_;  // since the last kStepDone
  uint32_t delivery_count_ = 0, confirm_count_ = 0, counter_count_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  int fd = -1;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--fd" && i + 1 < argc) {
      char* end = nullptr;
      const long v = std::strtol(argv[++i], &end, 10);
      if (*end == '\0' && v >= 0 && v < 65536) fd = static_cast<int>(v);
    } else if (a == "--help") {
      std::printf(
          "usage: uavsim-ns3-radio --fd N\n"
          "The ns3 radio backend of uavsim-server, which spawns it: not for running by hand.\n"
          "GPL-2.0-only (it links ns-3); see the README beside its source.\n");
      return 0;
    }
  }
  if (fd < 0) {
    std::fprintf(stderr, "uavsim-ns3-radio: needs --fd N (the server's end of a socket pair)\n");
    return 2;
  }
  return Helper(fd).run();
}
