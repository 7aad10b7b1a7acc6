// The sim API's ops by name (docs/protocol.md): every op group (ClockOps, EventOps, LockstepOps,
// VehicleOps, FrameStream, RadioOps, SensorOps, OverlayOps) registers its ops here,
// and the server dispatches requests, lists the ops in its hello and refuses unknown ones from this
// one table.
//
// Threads: the table is filled before the server starts and only read afterwards (the I/O thread
// looks names up, the loop thread runs the handlers).
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

#include "api/request_fields.hpp"
#include "uavsim/common/api_error.hpp"

namespace uavsim::server::api {

using common::ApiError;

// What an op handler answers: a result, an error (a typed code and a message), or nothing yet
// (deferred: the op replies later itself, as step does once its steps have run).
struct OpReply {
  nlohmann::json result = nlohmann::json::object();
  std::optional<ApiError> error;
  std::string message;
  bool deferred = false;

  void fail(ApiError code, std::string error_message) {
    error = code;
    message = std::move(error_message);
  }
  bool failed() const { return error.has_value(); }
};

// The wire form of a reply to the request with this id: {"id", "ok": true, "result"}, and
// {"id", "ok": false, "error": {"code", "message"}} (docs/protocol.md).
nlohmann::json ok_reply(const nlohmann::json& id, nlohmann::json result);
nlohmann::json error_reply(const nlohmann::json& id, ApiError code, const std::string& message);

// Where an op is answered.
enum class OpThread {
  kLoop,  // on the loop thread inside the control gate, in arrival order (every op that reads the
          // sim)
  kIo,    // by the transport on the I/O thread, before any queueing (auth); it has no handler
};

// Handles one request of its op on the loop thread; conn is the requesting connection.
using OpHandler = std::function<void(uint64_t conn, const nlohmann::json& request, OpReply* reply)>;

struct OpSpec {
  OpSpec(std::string op_name, std::string op_group, OpHandler op_handler,
         std::span<const FieldSpec> fields = {}, OpThread op_thread = OpThread::kLoop)
      : name(std::move(op_name)),
        group(std::move(op_group)),
        handler(std::move(op_handler)),
        typed_fields(fields),
        thread(op_thread) {}

  std::string name;
  std::string
      group;  // the op group that registered it ("clock", "vehicle", "camera", "radio", ...)
  OpHandler handler;  // null for OpThread::kIo
  // fields checked before the handler runs: a request naming one with another type gets bad_field
  // and the handler never sees it (no op half-applies a request); groups that check their own leave
  // it empty
  std::span<const FieldSpec> typed_fields;
  OpThread thread = OpThread::kLoop;
};

class OpTable {
 public:
  // Registers an op. A name registered twice is a programming error between groups: throws
  // std::logic_error naming it (at startup, before the server starts).
  void add(OpSpec spec);
  // The op with this name, or null. Thread-safe once the server runs (read-only).
  const OpSpec* find(std::string_view name) const;
  // Every op name, in registration order (the hello's "ops"). Thread-safe once the server runs.
  std::vector<std::string> names() const;

 private:
  std::vector<OpSpec> ops_;                           // in registration order
  std::map<std::string, size_t, std::less<>> index_;  // name -> ops_ index
};

// Registers the ops of one group whose handlers are the group's own member functions, each under
// the group's name and with the core ops' typed fields unless it names its own:
//   OpRegistrar<ClockOps> add(table, this, "clock");
//   add("status", &ClockOps::op_status);
// A member may take (conn, request, reply), (request, reply) or (reply) alone.
template <class Group>
class OpRegistrar {
 public:
  OpRegistrar(OpTable& table, Group* group, std::string group_name,
              std::span<const FieldSpec> fields = core_op_fields())
      : table_(table), group_(group), name_(std::move(group_name)), fields_(fields) {}

  template <class Member>
  void operator()(const char* op, Member member) const {
    (*this)(op, member, fields_);
  }
  template <class Member>
  void operator()(const char* op, Member member, std::span<const FieldSpec> fields) const {
    Group* g = group_;
    table_.add(
        {op, name_,
         [g, member](uint64_t conn, const nlohmann::json& request, OpReply* reply) {
           using Json = nlohmann::json;
           if constexpr (std::is_invocable_v<Member, Group*, uint64_t, const Json&, OpReply*>)
             std::invoke(member, g, conn, request, reply);
           else if constexpr (std::is_invocable_v<Member, Group*, const Json&, OpReply*>)
             std::invoke(member, g, request, reply);
           else
             std::invoke(member, g, reply);
         },
         fields});
  }

 private:
  OpTable& table_;
  Group* group_;
  std::string name_;
  std::span<const FieldSpec> fields_;
};

// An op group: registers its ops in the server's table and hears the loop-side hooks of the server.
// Every hook runs on the loop thread; the group must outlive the server.
class OpGroup {
 public:
  using Json = nlohmann::json;
  using Send = std::function<void(uint64_t conn, const Json& message)>;
  // Whether a connection gates the clock now (lockstep): it cannot act between its ticks, so what
  // is due for it may wait for before_tick.
  using InLockstep = std::function<bool(uint64_t conn)>;
  virtual ~OpGroup() = default;
  // Adds this group's ops to table. Called once, by ApiServer::add_group, before the server starts.
  virtual void register_ops(OpTable& table) = 0;
  // At every pass of the gate, before tick announcements: push async messages with send, so what
  // the group sends for sim time t reaches a lockstep client before tick t.
  virtual void on_gate(const Send& send, const InLockstep& in_lockstep) {
    (void)send;
    (void)in_lockstep;
  }
  // A tick is about to be announced to conn: whatever is due for it at the tick must be sent by
  // now (with send).
  virtual void before_tick(uint64_t conn, const Send& send) {
    (void)conn;
    (void)send;
  }
  // Whether conn has output of the current sim time prepared before it joined lockstep now (camera
  // frames are captured at the start of a step, before the API's requests): such a connection's
  // first tick cannot be now, or what is due for it at that tick was prepared without the lockstep
  // promise.
  virtual bool prepared_before_join(uint64_t conn) const {
    (void)conn;
    return false;
  }
  // The simulation was reset: sim time starts again at 0.
  virtual void on_reset() {}
  // A connection closed.
  virtual void on_disconnect(uint64_t conn) { (void)conn; }
};

}  // namespace uavsim::server::api
