#include "app/run_reporter.hpp"

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

namespace uavsim::server::app {

std::string console_line(const ReportedEvent& event, const std::string& vehicle_name) {
  char stamp[32];
  std::snprintf(stamp, sizeof(stamp), "t=%.3f ", event.time_s);
  std::string line = std::string("uavsim-server: ") + stamp;
  if (!vehicle_name.empty()) line += vehicle_name + ": ";
  line += event.kind;
  if (!event.detail.empty()) line += " " + event.detail;
  return line;
}

std::string json_line(const ReportedEvent& event, const std::string& vehicle_name) {
  nlohmann::json j;
  j["t"] = std::round(event.time_s * 1e6) / 1e6;  // sim time to the microsecond, not 2.00599999999989
  j["vehicle"] = event.vehicle;
  if (!vehicle_name.empty()) j["name"] = vehicle_name;
  j["event"] = event.kind;
  j["detail"] = event.detail;
  // a status text or a peer address may hold any byte: replace what is not UTF-8
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

RunReporter::RunReporter(sim::Simulation& sim, std::ostream* console, common::RecordFile* json,
                         std::ostream* errors)
    : sim_(sim), console_(console), json_(json), errors_(errors) {}

void RunReporter::report(const ReportedEvent& event) {
  const std::string name =
      event.vehicle >= 0 && static_cast<std::size_t>(event.vehicle) < sim_.vehicle_count()
          ? sim_.vehicle_name(static_cast<std::size_t>(event.vehicle))
          : std::string();
  if (console_ != nullptr) *console_ << console_line(event, name) << std::endl;
  if (json_ != nullptr && !json_->write(json_line(event, name) + "\n") && !json_failed_) {
    json_failed_ = true;
    if (errors_ != nullptr) *errors_ << "uavsim-server: the event log stops here: " << json_->error() << std::endl;
  }
}

void RunReporter::on_control_step() {
  const sim::EventLog& log = sim_.events();
  // a reset (sim API) clears the simulation's log: start again from its beginning
  if (log.next_seq() < next_event_) next_event_ = 0;
  for (const sim::Event& e : log.recent()) {
    if (e.seq < next_event_) continue;
    if (e.type == sim::EventType::kCrash) ++crashes_;
    std::string kind = e.type == sim::EventType::kModeChange ? "mode" : sim::event_type_name(e.type);
    report({e.time_s, e.vehicle, std::move(kind), e.detail});
  }
  next_event_ = log.next_seq();
}

void RunReporter::on_client(std::size_t vehicle, bool connected, const std::string& peer) {
  if (connected) ++clients_connected_;
  report({sim_.time_s(), static_cast<int>(vehicle), connected ? "client_connected" : "client_left",
          "MAVLink " + peer});
}

void RunReporter::on_status_text(std::size_t vehicle, int severity, const std::string& text) {
  // MAV_SEVERITY: 0 emergency, 1 alert, 2 critical, 3 error; the flight controller's failsafes say so
  if (severity > 3) return;
  const bool failsafe = text.find("ailsafe") != std::string::npos && text.find("Cleared") == std::string::npos;
  if (failsafe) {
    ++failsafes_;
    recent_failsafes_.push_back({sim_.time_s(), static_cast<int>(vehicle), "failsafe", text});
    if (recent_failsafes_.size() > kRecentFailsafes) recent_failsafes_.pop_front();
  }
  report({sim_.time_s(), static_cast<int>(vehicle), failsafe ? "failsafe" : "message", text});
}

void RunReporter::print_summary(std::ostream& out, const std::string& extra) const {
  const double wall_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - started_).count();
  const double sim_s = sim_.time_s();
  char line[256];
  std::snprintf(line, sizeof(line), "uavsim-server: ran %.3f s of sim time in %.1f s of wall time (%.2fx real time)",
                sim_s, wall_s, wall_s > 0 ? sim_s / wall_s : 0.0);
  out << line << "; " << sim_.vehicle_count() << " vehicle(s), " << crashes_ << " crash(es), " << failsafes_
      << " failsafe(s), " << clients_connected_ << " MAVLink client connection(s)";
  if (!extra.empty()) out << "; " << extra;
  out << std::endl;
}

}  // namespace uavsim::server::app
