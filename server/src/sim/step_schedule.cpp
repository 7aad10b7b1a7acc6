#include "sim/step_schedule.hpp"

#include <algorithm>
#include <sstream>

namespace uavsim::server::sim {

const char* phase_name(Phase phase) {
  switch (phase) {
    case Phase::kCapture:
      return "capture";
    case Phase::kQueuedTasks:
      return "queued_tasks";
    case Phase::kFlightControl:
      return "flight_control";
    case Phase::kPostControl:
      return "post_control";
    case Phase::kPrePhysics:
      return "pre_physics";
    case Phase::kPhysics:
      return "mj_step";
    case Phase::kContacts:
      return "contacts";
  }
  return "?";
}

bool control_phase(Phase phase) { return phase <= Phase::kPostControl; }

void StepSchedule::add(Phase phase, std::string name, Callback callback, Slot slot) {
  trail_names_.push_back(std::string(phase_name(phase)) + "/" + name);
  Entry entry{std::move(name), std::move(callback), slot, trail_names_.back().c_str()};
  if (running_) {
    pending_.push_back(Pending{phase, std::move(entry)});
    return;
  }
  insert(phase, std::move(entry));
}

void StepSchedule::insert(Phase phase, Entry entry) {
  // after every entry of the same or an earlier slot: registration order within a slot
  std::vector<Entry>& list = phases_[static_cast<std::size_t>(phase)];
  const auto at =
      std::find_if(list.begin(), list.end(), [&](const Entry& e) { return e.slot > entry.slot; });
  list.insert(at, std::move(entry));
}

void StepSchedule::add_contact_handler(std::string name, ContactHandler handler) {
  (running_ ? pending_handlers_ : contact_handlers_)
      .emplace_back(std::move(name), std::move(handler));
}

void StepSchedule::add_reset(std::string name, ResetHook hook) {
  (running_ ? pending_resets_ : reset_hooks_).emplace_back(std::move(name), std::move(hook));
}

void StepSchedule::add_pending() {
  for (Pending& p : pending_) insert(p.phase, std::move(p.entry));
  pending_.clear();
  for (auto& h : pending_handlers_) contact_handlers_.push_back(std::move(h));
  pending_handlers_.clear();
  for (auto& r : pending_resets_) reset_hooks_.push_back(std::move(r));
  pending_resets_.clear();
}

void StepSchedule::run_step(bool control) {
  // the lists do not change while they are walked: registrations made now wait for the step's end
  running_ = true;
  const std::size_t first = control ? 0 : static_cast<std::size_t>(Phase::kPrePhysics);
  for (std::size_t p = first; p < kPhaseCount; ++p) {
    for (Entry& e : phases_[p]) {
      activity_.enter(e.trail);
      e.callback();
    }
  }
  running_ = false;
  if (!pending_.empty() || !pending_handlers_.empty() || !pending_resets_.empty()) add_pending();
}

bool StepSchedule::handle_contact(const physics::VehicleContact& contact) {
  for (auto& [name, handler] : contact_handlers_) {
    if (handler(contact)) return true;
  }
  return false;
}

void StepSchedule::reset(uint64_t seed) {
  const bool was_running = running_;
  running_ = true;
  for (auto& [name, hook] : reset_hooks_) hook(seed);
  running_ = was_running;
  if (!running_) add_pending();
}

std::vector<std::string> StepSchedule::names(Phase phase) const {
  std::vector<std::string> out;
  for (const Entry& e : phases_[static_cast<std::size_t>(phase)]) out.push_back(e.name);
  return out;
}

std::vector<std::string> StepSchedule::contact_handler_names() const {
  std::vector<std::string> out;
  for (const auto& h : contact_handlers_) out.push_back(h.first);
  return out;
}

std::vector<std::string> StepSchedule::reset_names() const {
  std::vector<std::string> out;
  for (const auto& r : reset_hooks_) out.push_back(r.first);
  return out;
}

namespace {

// "a, b x3, c": runs of one name written once with their count
void write_names(std::ostringstream& out, const std::vector<std::string>& names) {
  if (names.empty()) out << "-";
  for (std::size_t i = 0; i < names.size();) {
    std::size_t n = 1;
    while (i + n < names.size() && names[i + n] == names[i]) ++n;
    out << (i > 0 ? ", " : "") << names[i];
    if (n > 1) out << " x" << n;
    i += n;
  }
}

}  // namespace

std::string StepSchedule::describe() const {
  std::ostringstream out;
  for (std::size_t p = 0; p < kPhaseCount; ++p) {
    const Phase phase = static_cast<Phase>(p);
    out << phase_name(phase) << (control_phase(phase) ? " (control steps): " : ": ");
    write_names(out, names(phase));
    if (phase == Phase::kContacts && !contact_handlers_.empty()) {
      out << "; contact handlers: ";
      write_names(out, contact_handler_names());
    }
    out << "\n";
  }
  out << "reset: ";
  write_names(out, reset_names());
  out << "\n";
  return out.str();
}

}  // namespace uavsim::server::sim
