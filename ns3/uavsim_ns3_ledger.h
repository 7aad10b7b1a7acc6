// SPDX-License-Identifier: GPL-2.0-only
// Copyright the uavsim authors.
//
// uavsim-ns3-radio's ledger of the frames it handed to the MACs (GPL-2.0-only like the helper,
// README.md here): what each one did (on air, received, confirmed), turned into the deliveries,
// confirms and counters of the next kStepDone (wire.hpp). Both technologies report into it, by
// the uid of the packet handed over; the lockstep loop is in uavsim_ns3_radio.cc.
#pragma once

#include <cstdint>
#include <map>
#include <utility>
#include <vector>

#include "ns3/packet.h"
#include "ns3/simulator.h"
#include "uavsim_ns3_parts.h"
#include "wire.hpp"

namespace uavsim_ns3 {

// a frame's receptions end a propagation delay after its sender's confirm (microseconds at radio
// ranges); counters are settled this long after the confirm
inline constexpr int64_t kSettle_ns = 100000;

class FrameLedger {
 public:
  // Forgets every frame and report; loss tells the receivers' power at a transmission's end.
  void reset(uint32_t vehicles, ns3::Ptr<UavsimLinkLoss> loss) {
    vehicles_ = vehicles;
    loss_ = loss;
    frames_.clear();
    deliveries_ = confirms_ = counters_ = uavsim::ns3wire::Writer();
    delivery_count_ = confirm_count_ = counter_count_ = 0;
  }
  // A frame handed over as the packet with uid: in the ledger (the helper busy) until settled.
  void add(uint64_t uid, Frame f) { frames_.emplace(uid, std::move(f)); }
  bool unconfirmed_broadcast(uint64_t uid) const {
    auto it = frames_.find(uid);
    return it != frames_.end() && it->second.to < 0 && it->second.confirmed_ns < 0;
  }

  void tx_begin(uint32_t vehicle, uint64_t uid) {
    // the data frame's first time on air (ACKs and unknown packets are not ours to count)
    auto it = frames_.find(uid);
    if (it == frames_.end() || it->second.from != vehicle || it->second.tx_start_ns >= 0) return;
    Frame& f = it->second;
    f.tx_start_ns = ns3::Simulator::Now().GetNanoSeconds();
    counter(f.from, f.from, uavsim::ns3wire::Counter::kTransmitted);
    for (uint32_t r = 0; r < vehicles_; ++r) {
      if (r == f.from || (f.to >= 0 && static_cast<uint32_t>(f.to) != r)) continue;
      counter(f.from, r, uavsim::ns3wire::Counter::kSent);
    }
  }

  void tx_end(uint32_t vehicle, uint64_t uid) {
    // the channel computed every receiver's power when this transmission started
    auto it = frames_.find(uid);
    if (it == frames_.end() || it->second.from != vehicle) return;
    for (uint32_t r = 0; r < vehicles_; ++r) {
      if (r != vehicle) it->second.rx_dbm[r] = loss_->last_dbm(vehicle, r);
    }
    if (it->second.tx_end_ns < 0) it->second.tx_end_ns = ns3::Simulator::Now().GetNanoSeconds();
  }

  void deliver(uint32_t vehicle, int64_t from, ns3::Ptr<const ns3::Packet> p, uint8_t lqi) {
    auto it = frames_.find(p->GetUid());
    if (it == frames_.end()) return;
    Frame& f = it->second;
    if (from != static_cast<int64_t>(f.from) || f.received[vehicle]) return;  // a retry's copy
    f.received[vehicle] = 1;
    counter(f.from, vehicle, uavsim::ns3wire::Counter::kDelivered);
    std::vector<uint8_t> data(p->GetSize());
    p->CopyData(data.data(), static_cast<uint32_t>(data.size()));
    uavsim::ns3wire::Writer& w = deliveries_;
    w.put(vehicle);
    w.put(f.from);
    w.put(f.seq);
    w.put<uint8_t>(f.to < 0 ? 1 : 0);
    w.put(f.queued_ns);
    w.put(f.tx_start_ns);
    w.put(ns3::Simulator::Now().GetNanoSeconds());
    w.put(lqi);
    w.put(static_cast<uint16_t>(data.size()));
    w.bytes(data.data(), data.size());
    ++delivery_count_;
  }

  void confirm(uint32_t vehicle, uint64_t uid, uavsim::ns3wire::ConfirmStatus status) {
    auto it = frames_.find(uid);
    if (it == frames_.end() || it->second.confirmed_ns >= 0) return;
    Frame& f = it->second;
    f.confirmed_ns = ns3::Simulator::Now().GetNanoSeconds();
    if (status == uavsim::ns3wire::ConfirmStatus::kChannelAccessFailure) {
      counter(vehicle, vehicle, uavsim::ns3wire::Counter::kChannelAccessFailure);
    }
    if (status == uavsim::ns3wire::ConfirmStatus::kNoAck) {
      counter(vehicle, static_cast<uint32_t>(f.to), uavsim::ns3wire::Counter::kNoAck);
    }
    confirms_.put(vehicle);
    confirms_.put(f.seq);
    confirms_.put(static_cast<uint8_t>(status));
    ++confirm_count_;
  }

  // frames confirmed long enough ago that every reception has ended: each intended receiver that
  // did not get a frame that went on air counts once, below sensitivity or lost (interference,
  // SINR errors, busy receiving or sending)
  void settle(double sensitivity_dbm) {
    const int64_t now_ns = ns3::Simulator::Now().GetNanoSeconds();
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
          const bool heard = f.rx_dbm[r] >= sensitivity_dbm;
          counter(f.from, r,
                  heard ? uavsim::ns3wire::Counter::kLost : uavsim::ns3wire::Counter::kOutOfRange);
        }
      }
      it = frames_.erase(it);
    }
  }

  // Frames in flight (not yet settled).
  bool busy() const { return !frames_.empty(); }
  // The earliest time at which the frames in flight can report anything (parts.h).
  int64_t quiet_until() const {
    return quiet_until_ns(frames_, ns3::Simulator::Now().GetNanoSeconds(), kSettle_ns);
  }

  // busy, quiet_until_ns (as busy() and quiet_until() said when the server's inputs were in: a
  // step run ahead reports those, wire.hpp) and the deliveries, confirms and counters since the
  // last report, into w (kStepDone after its time)
  void report(uavsim::ns3wire::Writer& w, bool busy, int64_t quiet_until_ns) {
    w.put<uint8_t>(busy ? 1 : 0);
    w.put(quiet_until_ns);
    auto append = [&w](uint32_t count, const uavsim::ns3wire::Writer& part) {
      w.put(count);
      const std::vector<uint8_t> m = part.message();
      w.bytes(m.data() + 4, m.size() - 4);
    };
    append(delivery_count_, deliveries_);
    append(confirm_count_, confirms_);
    append(counter_count_, counters_);
    deliveries_ = confirms_ = counters_ = uavsim::ns3wire::Writer();
    delivery_count_ = confirm_count_ = counter_count_ = 0;
  }

 private:
  void counter(uint32_t from, uint32_t to, uavsim::ns3wire::Counter c) {
    counters_.put(from);
    counters_.put(to);
    counters_.put(static_cast<uint8_t>(c));
    ++counter_count_;
  }

  uint32_t vehicles_ = 0;
  ns3::Ptr<UavsimLinkLoss> loss_;
  std::map<uint64_t, Frame> frames_;                          // by packet uid, until settled
  uavsim::ns3wire::Writer deliveries_, confirms_, counters_;  // since the last report
  uint32_t delivery_count_ = 0, confirm_count_ = 0, counter_count_ = 0;
};

}  // namespace uavsim_ns3
