// SPDX-License-Identifier: GPL-2.0-only
// Copyright the uavsim authors.
//
// Parts of uavsim-ns3-radio (GPL-2.0-only like the helper, README.md here): its propagation loss
// model, the record of a frame handed to a MAC, and the vehicles' short addresses. Kept apart from
// the helper's lockstep loop (uavsim_ns3_radio.cc).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <vector>

#include "ns3/mac16-address.h"
#include "ns3/mobility-model.h"
#include "ns3/node.h"
#include "ns3/propagation-loss-model.h"
#include "wire.hpp"

namespace uavsim_ns3 {

// The loss uavsim adds after ns-3's log-distance and shadowing models: the range model (every
// receiver within range hears the transmit power), the server's transmit power, the extra loss of
// a blocked path (obstacles, pushed by the server per link) and the receiver sensitivity, which
// ns-3 3.37 cannot set on lr-wpan's PHY (its own floor is about -106.6 dBm): a signal below it is
// cut to -1000 dBm (heard by no one, interfering with no one). It records each link's last result
// so the helper can tell "below sensitivity" from "lost" when it settles a frame's counters.
class UavsimLinkLoss : public ns3::PropagationLossModel {
 public:
  static ns3::TypeId GetTypeId() {
    static ns3::TypeId tid = ns3::TypeId("uavsim::UavsimLinkLoss")
                                 .SetParent<ns3::PropagationLossModel>()
                                 .SetGroupName("uavsim");
    return tid;
  }
  void configure(const uavsim::ns3wire::Channel& c, uint32_t vehicles) {
    channel_ = c;
    vehicles_ = vehicles;
    extra_db_.assign(static_cast<size_t>(vehicles) * vehicles, 0.0);
    last_dbm_.assign(static_cast<size_t>(vehicles) * vehicles, -1000.0);
  }
  void set_channel(const uavsim::ns3wire::Channel& c) { channel_ = c; }
  void set_extra(uint32_t from, uint32_t to, double db) {
    extra_db_[static_cast<size_t>(from) * vehicles_ + to] = db;
  }
  double last_dbm(uint32_t from, uint32_t to) const {
    return last_dbm_[static_cast<size_t>(from) * vehicles_ + to];
  }

 private:
  double DoCalcRxPower(double tx_dbm, ns3::Ptr<ns3::MobilityModel> a,
                       ns3::Ptr<ns3::MobilityModel> b) const override {
    const uint32_t from = a->GetObject<ns3::Node>()->GetId();
    const uint32_t to = b->GetObject<ns3::Node>()->GetId();
    const double extra_db = extra_db_[static_cast<size_t>(from) * vehicles_ + to];
    double rx_dbm = tx_dbm + channel_.tx_power_dbm - extra_db;
    if (!channel_.log_distance) {
      // a loss of L dB shrinks the range as the log-distance law would (as the simple backend does)
      const double range_m =
          channel_.range_m * std::pow(10.0, -extra_db / (10.0 * channel_.path_loss_exponent));
      rx_dbm = a->GetDistanceFrom(b) <= range_m ? tx_dbm + channel_.tx_power_dbm : -1000.0;
    }
    if (rx_dbm < channel_.sensitivity_dbm) rx_dbm = -1000.0;
    last_dbm_[static_cast<size_t>(from) * vehicles_ + to] = rx_dbm;
    return rx_dbm;
  }
  int64_t DoAssignStreams(int64_t) override { return 0; }

  uavsim::ns3wire::Channel channel_;
  uint32_t vehicles_ = 0;
  std::vector<double> extra_db_;
  mutable std::vector<double> last_dbm_;
};

// A frame handed to a MAC, until its counters are settled.
struct Frame {
  uint32_t from = 0;
  int32_t to = -1;  // -1: broadcast
  uint64_t seq = 0;
  int64_t queued_ns = 0;
  int64_t request_ns = -1;        // handed to the MAC (now, or at its TDMA slot)
  int64_t airtime_ns = 0;         // its PPDU on air (PHY header, MAC header, payload)
  int64_t tx_start_ns = -1;       // first time on air; -1: never
  int64_t tx_end_ns = -1;         // end of its first transmission; -1: not yet
  int64_t confirmed_ns = -1;      // the MAC's confirm; -1: not yet
  std::vector<uint8_t> received;  // per vehicle: delivered
  std::vector<double> rx_dbm;     // per vehicle: at the last transmission's end
};

inline ns3::Mac16Address address(uint32_t i) {
  // short addresses 1..N (0xffff is broadcast, 0xfffe "no short address")
  const uint16_t a = static_cast<uint16_t>(i + 1);
  const uint8_t b[2] = {static_cast<uint8_t>(a >> 8), static_cast<uint8_t>(a & 0xff)};
  ns3::Mac16Address m;
  m.CopyFrom(b);
  return m;
}
inline int64_t index_of(const ns3::Mac16Address& m) {
  uint8_t b[2];
  m.CopyTo(b);
  return (static_cast<int64_t>(b[0]) << 8 | b[1]) - 1;
}

// The earliest time the helper can have anything to report on frames (by packet uid, at now_ns: a
// reception, a confirm, a frame to settle settle_ns after its confirm), so the server need not step
// it before: a frame not yet handed to its MAC (a TDMA slot to come) or on air ends one airtime
// after it starts at the earliest, and receptions and a broadcast's confirm come at its end. A
// frame in CSMA-CA, waiting for its ACK or being retried may report at any time: now. INT64_MAX:
// nothing in flight.
inline int64_t quiet_until_ns(const std::map<uint64_t, Frame>& frames, int64_t now_ns,
                              int64_t settle_ns) {
  int64_t until_ns = std::numeric_limits<int64_t>::max();
  for (const auto& [uid, f] : frames) {
    int64_t at_ns = now_ns;
    if (f.confirmed_ns >= 0) {
      at_ns = f.confirmed_ns + settle_ns;
    } else if (f.tx_start_ns >= 0 && f.tx_end_ns < 0) {
      at_ns = f.tx_start_ns + f.airtime_ns;
    } else if (f.tx_start_ns < 0 && f.request_ns > now_ns) {
      at_ns = f.request_ns + f.airtime_ns;
    }
    until_ns = std::min(until_ns, at_ns);
  }
  return until_ns;
}

}  // namespace uavsim_ns3
