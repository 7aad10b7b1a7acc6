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
#include "uavsim_ns3_ledger.h"
#include "uavsim_ns3_parts.h"
#include "uavsim_ns3_wifi.h"
#include "wire.hpp"

namespace {

using namespace ns3;
namespace wire = uavsim::ns3wire;
using uavsim_ns3::address;
using uavsim_ns3::Frame;
using uavsim_ns3::FrameLedger;
using uavsim_ns3::index_of;
using uavsim_ns3::install_wifi;
using uavsim_ns3::kWifiProtocol;
using uavsim_ns3::UavsimLinkLoss;

constexpr uint16_t kPanId = 1;
// 802.15.4 data frame with short addresses and a compressed PAN id: frame control 2, sequence 1,
// destination PAN 2, destination 2, source 2, FCS 2
constexpr uint32_t kMacHeaderBytes = 11;
constexpr uint32_t kMaxPayloadBytes = 127 - kMacHeaderBytes;
// 802.11's MSDU carries up to 2304 bytes; uavsim offers an Ethernet MTU's 1500 (wire.hpp)
constexpr uint32_t kMaxWifiPayloadBytes = wire::kMaxFrameBytes;
// 802.15.4's default macMinBE (ns-3's too): the random backoff of unslotted CSMA-CA
constexpr uint8_t kStandardMacMinBE = 3;
// O-QPSK 250 kbit/s: 32 us a byte; the PHY's preamble, delimiter and length take 6 bytes
constexpr int64_t kByte_ns = 32000;
constexpr uint32_t kPhyHeaderBytes = 6;
// slices in one kStep: the server sends at most a few a step (its API gate's and its physics
// step's); anything far beyond is a malformed message
constexpr uint32_t kMaxSlices = 64;

class Helper {
 public:
  explicit Helper(int fd) : fd_(fd) {
    wifi_hooks_.tx_begin = [this](uint32_t v, uint64_t uid) { ledger_.tx_begin(v, uid); };
    wifi_hooks_.tx_end = [this](uint32_t v, uint64_t uid) {
      ledger_.tx_end(v, uid);
      // a broadcast is done once on air (no ACK, no retry)
      if (ledger_.unconfirmed_broadcast(uid))
        ledger_.confirm(v, uid, wire::ConfirmStatus::kSuccess);
    };
    wifi_hooks_.rx = [this](uint32_t v, const Address& from, Ptr<const Packet> p) {
      ledger_.deliver(v, uavsim_ns3::wifi_index_of(wifi_, from), p, 255);
    };
    wifi_hooks_.done = [this](uint32_t v, uint64_t uid, bool acked, bool retry_limit) {
      ledger_.confirm(v, uid,
                      acked         ? wire::ConfirmStatus::kSuccess
                      : retry_limit ? wire::ConfirmStatus::kNoAck
                                    : wire::ConfirmStatus::kOther);
    };
  }

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
          if (!build(seed)) return error("802.11 traces did not connect");
          sent = ready();
          break;
        }
        case wire::MessageType::kConfig: {
          const wire::Channel c = wire::get_channel(in);
          if (!in.ok() || vehicles_ == 0) return error("malformed config");
          // another technology is another set of devices: a fresh world (frames in flight dropped)
          const bool rebuild = c.technology != channel_.technology;
          channel_ = c;
          if (rebuild && !build(seed_)) return error("802.11 traces did not connect");
          if (!rebuild) apply_channel();
          sent = ready();
          break;
        }
        case wire::MessageType::kReset: {
          const auto seed = in.get<uint64_t>();
          if (!in.ok() || vehicles_ == 0) return error("malformed reset");
          if (!build(seed)) return error("802.11 traces did not connect");
          sent = ready();
          break;
        }
        case wire::MessageType::kStep: {
          if (vehicles_ == 0) return error("step before init");
          const auto slices = in.get<uint32_t>();
          if (!in.ok() || slices > kMaxSlices) return error("malformed step");
          for (uint32_t k = 0; k < slices; ++k) {
            if (!slice(in)) return error("malformed step");
          }
          const auto ahead_ns = in.get<int64_t>();
          if (!in.ok() || in.left() != 0) return error("malformed step");
          sent = step_done(ahead_ns);
          break;
        }
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
    w.put(max_payload());
    return wire::write_all(fd_, w.message()) == wire::IoResult::kOk;
  }

  bool wifi() const { return channel_.technology == 1; }
  uint32_t max_payload() const { return wifi() ? kMaxWifiPayloadBytes : kMaxPayloadBytes; }

  // a fresh ns-3 world: one node per vehicle on one 802.15.4 (or 802.11) channel (pitfall: one
  // ns-3 world per process, so a reset destroys the old one first and time restarts at 0)
  bool build(uint64_t seed) {
    Simulator::Destroy();
    seed_ = seed;
    wifi_.clear();
    macs_.clear();
    csmas_.clear();
    mobility_.clear();
    pending_.assign(vehicles_, {});
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
    ledger_.reset(vehicles_, link_loss_);
    log_distance_->SetNext(shadowing_);
    shadowing_->SetNext(link_loss_);
    channel_model_->AddPropagationLossModel(log_distance_);
    apply_channel();
    channel_model_->SetPropagationDelayModel(CreateObject<ConstantSpeedPropagationDelayModel>());
    for (uint32_t i = 0; i < vehicles_; ++i) {
      mobility_.push_back(nodes.Get(i)->GetObject<ConstantVelocityMobilityModel>());
    }
    int64_t stream = 0;
    if (wifi()) {
      const bool ok = install_wifi(nodes, log_distance_, &wifi_hooks_, &stream, &wifi_);
      shadowing_variable_->SetStream(stream);
      return ok;
    }

    // devices made by hand: LrWpanHelper::Install calls SetNode after Node::AddDevice already did,
    // and in 3.37 that second configuration leaves the channel delivering nothing (every unicast
    // ends in NO_ACK)
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
      // the PHY's own mobility: without it the channel applies no loss and no delay
      dev->GetPhy()->SetMobility(mobility_[i]);
      stream += dev->AssignStreams(stream);
    }
    shadowing_variable_->SetStream(stream);
    apply_mac();
    return true;
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

  // One slice of a kStep (wire.hpp): ns-3 to its time, then the server's inputs at that time.
  bool slice(wire::Reader& in) {
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
          f.to == static_cast<int32_t>(f.from) || n == 0 || n > max_payload() ||
          (at_ns != -1 && at_ns < t_ns) || !in.bytes(n, &data)) {
        return false;
      }
      hand(std::move(f), data, at_ns);
    }
    ledger_.settle(channel_.sensitivity_dbm);
    return in.ok();
  }

  // a frame to its sender's MAC, now (at_ns -1) or at at_ns (its TDMA slot, or the entry the
  // server drew to spread a step's frames): broadcast, or unicast with ACK and retries
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
    // 802.11: no airtime bound (quiet_until_ns then steps it every step while in flight)
    f.airtime_ns =
        wifi() ? 0
               : static_cast<int64_t>(data.size() + kMacHeaderBytes + kPhyHeaderBytes) * kByte_ns;
    const uint32_t from = f.from;
    const int32_t to = f.to;
    // in the ledger from now on: the helper stays busy until the frame is settled
    ledger_.add(p->GetUid(), std::move(f));
    if (wifi()) {
      const Mac48Address dest = to < 0 ? Mac48Address::GetBroadcast()
                                       : Mac48Address::ConvertFrom(wifi_[to]->GetAddress());
      if (at_ns < 0) {
        send_wifi(this, from, dest, p);
      } else {
        Simulator::Schedule(NanoSeconds(at_ns) - Simulator::Now(), &Helper::send_wifi, this, from,
                            dest, p);
      }
    } else if (at_ns < 0) {
      request(this, from, params, p);
    } else {
      Simulator::Schedule(NanoSeconds(at_ns) - Simulator::Now(), &Helper::request, this, from,
                          params, p);
    }
  }

  static void send_wifi(Helper* h, uint32_t from, Mac48Address to, Ptr<Packet> p) {
    h->wifi_[from]->Send(p, to, kWifiProtocol);
  }

  static void request(Helper* h, uint32_t from, McpsDataRequestParams params, Ptr<Packet> p) {
    // the MAC confirms in the order of its requests
    h->pending_[from].push_back(p->GetUid());
    h->macs_[from]->McpsDataRequest(params, p);
  }

  static void on_tx_begin(Helper* h, uint32_t vehicle, Ptr<const Packet> p) {
    h->ledger_.tx_begin(vehicle, p->GetUid());
  }
  static void on_tx_end(Helper* h, uint32_t vehicle, Ptr<const Packet> p) {
    h->ledger_.tx_end(vehicle, p->GetUid());
  }
  static void on_indication(Helper* h, uint32_t vehicle, McpsDataIndicationParams params,
                            Ptr<Packet> p) {
    h->ledger_.deliver(vehicle, index_of(params.m_srcAddr), p, params.m_mpduLinkQuality);
  }
  static void on_confirm(Helper* h, uint32_t vehicle, McpsDataConfirmParams params) {
    // a MAC confirms its requests in the order they were made
    if (h->pending_[vehicle].empty()) return;
    const uint64_t uid = h->pending_[vehicle].front();
    h->pending_[vehicle].pop_front();
    wire::ConfirmStatus status = wire::ConfirmStatus::kOther;
    if (params.m_status == IEEE_802_15_4_SUCCESS) status = wire::ConfirmStatus::kSuccess;
    if (params.m_status == IEEE_802_15_4_CHANNEL_ACCESS_FAILURE) {
      status = wire::ConfirmStatus::kChannelAccessFailure;
    }
    if (params.m_status == IEEE_802_15_4_NO_ACK) status = wire::ConfirmStatus::kNoAck;
    h->ledger_.confirm(vehicle, uid, status);
  }

  // The answer to a kStep, after running ahead to ahead_ns when the frames in flight would have
  // the server step there anyway (busy, and ahead_ns at or after their quiet time): the server
  // computes its next physics step meanwhile. busy and quiet_until go back as they were before
  // the run ahead, which is what the server decides its next steps by (wire.hpp).
  bool step_done(int64_t ahead_ns) {
    const bool busy = ledger_.busy();
    const int64_t quiet_until = ledger_.quiet_until();
    if (busy && ahead_ns > Simulator::Now().GetNanoSeconds() && ahead_ns >= quiet_until) {
      Simulator::Stop(NanoSeconds(ahead_ns) - Simulator::Now());
      Simulator::Run();
      ledger_.settle(channel_.sensitivity_dbm);
    }
    wire::Writer w;
    w.put(static_cast<uint8_t>(wire::MessageType::kStepDone));
    w.put(Simulator::Now().GetNanoSeconds());
    ledger_.report(w, busy, quiet_until);
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
  std::vector<Ptr<WifiNetDevice>> wifi_;  // 802.11: the devices (then no macs_)
  uavsim_ns3::WifiHooks wifi_hooks_;
  uint64_t seed_ = 0;
  std::vector<Ptr<ConstantVelocityMobilityModel>> mobility_;
  FrameLedger ledger_;
  std::vector<std::deque<uint64_t>> pending_;  // per sender: uids awaiting their confirm
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
