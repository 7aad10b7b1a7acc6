// SPDX-License-Identifier: GPL-2.0-only
// Copyright the uavsim authors.
//
// uavsim-ns3-radio's second technology: IEEE 802.11g ad hoc (ns-3's wifi module: AdhocWifiMac,
// ERP-OFDM at a fixed 6 Mbit/s through ConstantRateWifiManager, DCF with ACKs and retries for
// unicast) on the same nodes and the same loss chain as the 802.15.4 radios (README.md here). The
// helper's lockstep loop (uavsim_ns3_radio.cc) sees it through the hooks below, keyed by the uid of
// the packet it handed over (ns-3 keeps a packet's uid through its copies and headers).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "ns3/double.h"
#include "ns3/mac48-address.h"
#include "ns3/node-container.h"
#include "ns3/propagation-delay-model.h"
#include "ns3/propagation-loss-model.h"
#include "ns3/string.h"
#include "ns3/wifi-helper.h"
#include "ns3/wifi-mac-helper.h"
#include "ns3/wifi-mac.h"
#include "ns3/wifi-mpdu.h"
#include "ns3/wifi-net-device.h"
#include "ns3/yans-wifi-channel.h"
#include "ns3/yans-wifi-helper.h"

namespace uavsim_ns3 {

struct WifiHooks {
  std::function<void(uint32_t vehicle, uint64_t uid)> tx_begin;
  std::function<void(uint32_t vehicle, uint64_t uid)> tx_end;
  // a data frame received by vehicle from the device with address from (the payload, LLC header
  // removed)
  std::function<void(uint32_t vehicle, const ns3::Address& from, ns3::Ptr<const ns3::Packet>)> rx;
  // a unicast's end: acked, or dropped (retry_limit: no ACK after the retries)
  std::function<void(uint32_t vehicle, uint64_t uid, bool acked, bool retry_limit)> done;
};

// The vehicle whose device has address (-1: none). The devices keep the addresses ns-3 allocated
// them: a MAC whose address is changed after it was set up still takes ACKs for the old one.
inline int64_t wifi_index_of(const std::vector<ns3::Ptr<ns3::WifiNetDevice>>& devices,
                             const ns3::Address& address) {
  for (size_t i = 0; i < devices.size(); ++i) {
    if (devices[i]->GetAddress() == address) return static_cast<int64_t>(i);
  }
  return -1;
}

// The EtherType of uavsim's frames on 802.11 (IEEE's local experimental one).
inline constexpr uint16_t kWifiProtocol = 0x88B5;

// One 802.11g ad hoc radio per node on a YANS channel with loss (the caller's chain, which applies
// the transmit power) and a constant-speed delay; transmit power 0 dBm before that chain, as on
// lr-wpan. Pins the devices' random streams from *stream on. Every trace must connect: a wrong
// name would leave the helper counting nothing, so false (and nothing usable) if one does not.
// hooks must outlive the devices.
inline bool install_wifi(const ns3::NodeContainer& nodes, ns3::Ptr<ns3::PropagationLossModel> loss,
                         WifiHooks* hooks, int64_t* stream,
                         std::vector<ns3::Ptr<ns3::WifiNetDevice>>* out) {
  using namespace ns3;
  Ptr<YansWifiChannel> channel = CreateObject<YansWifiChannel>();
  channel->SetPropagationLossModel(loss);
  channel->SetPropagationDelayModel(CreateObject<ConstantSpeedPropagationDelayModel>());
  YansWifiPhyHelper phy;
  phy.SetChannel(channel);
  phy.Set("TxPowerStart", DoubleValue(0.0));
  phy.Set("TxPowerEnd", DoubleValue(0.0));
  WifiHelper wifi;
  wifi.SetStandard(WIFI_STANDARD_80211g);
  // broadcasts too (they would go at the lowest basic rate, DSSS 1 Mbit/s: 1.5 ms a frame)
  wifi.SetRemoteStationManager(
      "ns3::ConstantRateWifiManager", "DataMode", StringValue("ErpOfdmRate6Mbps"), "ControlMode",
      StringValue("ErpOfdmRate6Mbps"), "NonUnicastMode", StringValue("ErpOfdmRate6Mbps"));
  WifiMacHelper mac;
  mac.SetType("ns3::AdhocWifiMac");
  NetDeviceContainer devices = wifi.Install(phy, mac, nodes);
  *stream += wifi.AssignStreams(devices, *stream);
  out->clear();
  bool ok = true;
  for (uint32_t i = 0; i < devices.GetN(); ++i) {
    Ptr<WifiNetDevice> dev = DynamicCast<WifiNetDevice>(devices.Get(i));
    WifiHooks* h = hooks;
    dev->SetReceiveCallback(MakeBoundCallback(
        +[](WifiHooks* h, uint32_t v, Ptr<NetDevice>, Ptr<const Packet> p, uint16_t protocol,
            const Address& from) {
          if (protocol == kWifiProtocol) h->rx(v, from, p);
          return true;
        },
        h, i));
    ok = ok && dev->GetPhy()->TraceConnectWithoutContext(
                   "PhyTxBegin", MakeBoundCallback(
                                     +[](WifiHooks* h, uint32_t v, Ptr<const Packet> p, double) {
                                       h->tx_begin(v, p->GetUid());
                                     },
                                     h, i));
    ok = ok && dev->GetPhy()->TraceConnectWithoutContext(
                   "PhyTxEnd", MakeBoundCallback(
                                   +[](WifiHooks* h, uint32_t v, Ptr<const Packet> p) {
                                     h->tx_end(v, p->GetUid());
                                   },
                                   h, i));
    ok = ok && dev->GetMac()->TraceConnectWithoutContext(
                   "AckedMpdu", MakeBoundCallback(
                                    +[](WifiHooks* h, uint32_t v, Ptr<const WifiMpdu> m) {
                                      h->done(v, m->GetPacket()->GetUid(), true, false);
                                    },
                                    h, i));
    ok = ok && dev->GetMac()->TraceConnectWithoutContext(
                   "DroppedMpdu",
                   MakeBoundCallback(
                       +[](WifiHooks* h, uint32_t v, WifiMacDropReason r, Ptr<const WifiMpdu> m) {
                         h->done(v, m->GetPacket()->GetUid(), false,
                                 r == WIFI_MAC_DROP_REACHED_RETRY_LIMIT);
                       },
                       h, i));
    out->push_back(dev);
  }
  return ok;
}

}  // namespace uavsim_ns3
