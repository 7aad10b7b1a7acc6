#include "api/shm_transport.hpp"

#include <fcntl.h>
#include <sys/mman.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <span>

#include "api/request_ring.hpp"
#include "uavsim/common/shm_ring.hpp"

namespace uavsim::server::api {

namespace {

namespace shm = common::shm;

// 128 random bits in hex: the objects' names cannot be guessed (they are 0600 besides)
std::optional<std::string> random_token() {
  unsigned char bytes[16];
  size_t got = 0;
  while (got < sizeof(bytes)) {
    const ssize_t n = getrandom(bytes + got, sizeof(bytes) - got, 0);
    if (n < 0) {
      if (errno == EINTR) continue;
      return std::nullopt;
    }
    got += static_cast<size_t>(n);
  }
  static const char kHex[] = "0123456789abcdef";
  std::string token;
  for (unsigned char b : bytes) {
    token += kHex[b >> 4];
    token += kHex[b & 15];
  }
  return token;
}

// A wake-up FIFO at path, made here (0600) and opened read-write, so that the open does not wait
// for the client; -1 with *why (and no name left) if the system refuses.
int make_fifo(const std::string& path, std::string* why) {
  int fd = -1;
  if (mkfifo(path.c_str(), 0600) == 0) fd = open(path.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd < 0) {
    *why = "FIFO " + path + ": " + std::strerror(errno);
    unlink(path.c_str());
  }
  return fd;
}

}  // namespace

// One connection's ring: the mapping, the wake FIFO's write end, the writer.
class ShmTransport::Ring : public LineServer::Diversion {
 public:
  // mapping: the region (this ring at its start), unmapped when the last of its users goes
  Ring(uint64_t conn, std::string token, std::shared_ptr<void> mapping, std::size_t capacity,
       int fifo_fd, std::shared_ptr<Shared> shared)
      : conn_(conn),
        token_(std::move(token)),
        mapping_(std::move(mapping)),
        fifo_fd_(fifo_fd),
        shared_(std::move(shared)),
        writer_(mapping_.get(), capacity) {}

  ~Ring() override {
    unlink_names();
    close(fifo_fd_);  // the client's FIFO sees the hang-up
  }

  // LineServer::Diversion: a stream record with these bytes (whole messages)
  bool write(const std::string& data, bool work_ahead) override {
    const std::span<const uint8_t> part(reinterpret_cast<const uint8_t*>(data.data()), data.size());
    return write_record(shm::RecordType::kStream,
                        std::span<const std::span<const uint8_t>>(&part, 1),
                        /*ends_quiet=*/false, work_ahead);
  }

  std::size_t pending_bytes() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    return writer_.waiting_bytes();
  }

  // ends_quiet: a tick record, after which the connection may be waiting again; work_ahead: wakes
  // the reader even while quiet (LineServer::Diversion)
  bool write_record(shm::RecordType type, std::span<const std::span<const uint8_t>> parts,
                    bool ends_quiet = false, bool work_ahead = false) {
    bool wake_now = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (failed_) return false;
      std::string why;
      const auto error = writer_.write(type, parts, &why);
      if (error) {
        // said once: the connection is closed as overloaded
        failed_ = true;
        const char* what = *error == shm::RingError::kCorrupt
                               ? "the client broke its shared-memory ring"
                           : *error == shm::RingError::kFull
                               ? "the client's shared-memory ring is full (it does not read)"
                               : "a message larger than the client's shared-memory ring";
        std::fprintf(stderr, "sim API: connection %llu dropped: %s%s%s\n",
                     static_cast<unsigned long long>(conn_), what, why.empty() ? "" : ": ",
                     why.c_str());
        return false;
      }
      if (ends_quiet) quiet_ = false;
      owed_ = true;
      owed_work_ = owed_work_ || work_ahead;
      wake_now = settle();
    }
    if (wake_now) wake();
    return true;
  }

  // The end of a gate pass: the wake-up its writes owe, unless the client is quiet.
  void release() { set_quiet_and_settle(std::nullopt); }

  // Quiet (done accepted): what is written from now on, and what this pass wrote before, is read
  // with the next tick; not quiet: the reader is woken for it (at the end of the pass if held).
  void set_quiet(bool quiet) { set_quiet_and_settle(quiet); }

  void unlink_names() {
    if (unlinked_) return;
    unlinked_ = true;
    shm_unlink(shm::object_name(token_).c_str());
    unlink(shm::fifo_path(token_).c_str());
    unlink(shm::request_fifo_path(token_).c_str());
  }

  bool failed() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return failed_;
  }

  std::shared_ptr<RequestRing> requests;    // the client's request ring, if it asked for one
  std::vector<radio::Delivery> tick_radio;  // loop thread: the frames for the next tick record
  std::vector<uint8_t> tick_body;           // loop thread: those frames encoded (reused)

 private:
  void set_quiet_and_settle(std::optional<bool> quiet) {
    bool wake_now = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (quiet) quiet_ = *quiet;
      wake_now = settle();
    }
    if (wake_now) wake();
  }

  // mutex_ held. Takes the wake-up owed for the records written since the last one, unless the
  // gate pass holds wake-ups (release() settles it) or the client is quiet (the tick, or the end
  // of quiet, settles it). The reader's flag is taken only when the FIFO byte follows, so a
  // wake-up put off is never lost: the reader armed before the records were written still has its
  // flag clear when the wake-up is finally taken.
  bool settle() {
    if (!owed_ || (quiet_ && !owed_work_) || shared_->held.load()) return false;
    owed_ = false;
    owed_work_ = false;
    return writer_.take_wakeup();
  }

  void wake() {
    const char b = 1;
    // the flag allows one byte in flight: a full FIFO means the client wrote its own flag, and its
    // wake-up is there anyway
    if (::write(fifo_fd_, &b, 1) == 1) shared_->wakeups.fetch_add(1);
  }

  const uint64_t conn_;
  const std::string token_;
  const std::shared_ptr<void> mapping_;
  const int fifo_fd_;
  std::shared_ptr<Shared> shared_;
  mutable std::mutex mutex_;  // guards writer_, failed_, owed_, owed_work_ and quiet_
  shm::RingWriter writer_;
  bool failed_ = false;
  bool owed_ = false;      // records written whose wake-up is not taken yet
  bool owed_work_ = false;  // among them one the reader may work on ahead of its tick (a frame)
  bool quiet_ = false;     // done accepted, its next tick not written yet (quiet_until_tick)
  bool unlinked_ = false;  // loop thread (and the destructor)
};

ShmTransport::ShmTransport(LineServer& server) : server_(server) {}

ShmTransport::~ShmTransport() = default;

std::optional<nlohmann::json> ShmTransport::offer(uint64_t conn, std::size_t ring_bytes,
                                                  std::size_t request_ring_bytes,
                                                  std::string* why) {
  // the server's ring, then the client's request ring if it asked for one
  const std::size_t ring_region = shm::region_bytes(ring_bytes);
  const std::size_t request_region =
      request_ring_bytes == 0 ? 0 : shm::region_bytes(request_ring_bytes);
  const std::size_t region_size = ring_region + request_region;
  const auto token = random_token();
  if (ring_region == 0 || (request_ring_bytes != 0 && request_region == 0) || !token) {
    *why = token ? "bad ring size" : std::string("getrandom: ") + std::strerror(errno);
    return std::nullopt;
  }
  // the region: created here (never an object someone else made), 0600, sized, mapped
  const std::string name = shm::object_name(*token);
  const int fd = shm_open(name.c_str(), O_RDWR | O_CREAT | O_EXCL | O_CLOEXEC, 0600);
  if (fd < 0) {
    *why = "shm_open " + name + ": " + std::strerror(errno);
    return std::nullopt;
  }
  void* region = MAP_FAILED;
  if (ftruncate(fd, static_cast<off_t>(region_size)) == 0) {
    region = mmap(nullptr, region_size, PROT_READ | PROT_WRITE, MAP_SHARED, fd, 0);
  }
  const int map_errno = errno;
  close(fd);
  if (region == MAP_FAILED) {
    shm_unlink(name.c_str());
    *why = "mapping " + std::to_string(region_size) +
           " bytes of shared memory: " + std::strerror(map_errno);
    return std::nullopt;
  }
  std::shared_ptr<void> mapping(region, [region_size](void* r) { munmap(r, region_size); });
  const int fifo_fd = make_fifo(shm::fifo_path(*token), why);
  if (fifo_fd < 0) {
    shm_unlink(name.c_str());
    return std::nullopt;
  }
  auto ring = std::make_shared<Ring>(conn, *token, mapping, ring_bytes, fifo_fd, shared_);
  nlohmann::json result{{"token", *token}, {"ring_bytes", ring_bytes}, {"version", shm::kVersion}};
  if (request_ring_bytes != 0) {
    // (on failure the ring, going, unlinks the names made: the region's, both FIFOs')
    const int request_fifo_fd = make_fifo(shm::request_fifo_path(*token), why);
    if (request_fifo_fd < 0) return std::nullopt;
    ring->requests = RequestRing::create(mapping, static_cast<uint8_t*>(region) + ring_region,
                                         request_ring_bytes, request_fifo_fd, why);
    if (!ring->requests) return std::nullopt;
    result["request_ring_bytes"] = request_ring_bytes;
  }
  offered_[conn] = std::move(ring);
  return result;
}

void ShmTransport::activate(uint64_t conn) {
  auto it = offered_.find(conn);
  if (it == offered_.end()) return;
  std::shared_ptr<Ring> ring = std::move(it->second);
  offered_.erase(it);
  if (!server_.divert(conn, ring)) return;  // it closed meanwhile
  // its requests from now on (the client writes none there before it has read the offer's reply)
  if (ring->requests && !server_.add_intake(conn, ring->requests)) return;
  std::lock_guard<std::mutex> lock(mutex_);
  rings_[conn] = std::move(ring);
  activated_total_.fetch_add(1);
}

bool ShmTransport::attached(uint64_t conn) const {
  std::lock_guard<std::mutex> lock(mutex_);
  return rings_.count(conn) > 0;
}

void ShmTransport::set_tick_radio(uint64_t conn, std::vector<radio::Delivery> frames) {
  std::lock_guard<std::mutex> lock(mutex_);
  auto it = rings_.find(conn);
  if (it == rings_.end()) return;
  auto& pending = it->second->tick_radio;
  if (pending.empty()) {
    pending = std::move(frames);
  } else {
    pending.insert(pending.end(), std::make_move_iterator(frames.begin()),
                   std::make_move_iterator(frames.end()));
  }
}

bool ShmTransport::send_tick(uint64_t conn, int64_t tick, double time_s) {
  std::shared_ptr<Ring> ring;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    auto it = rings_.find(conn);
    if (it == rings_.end()) return false;
    ring = it->second;
  }
  // (tick, time, frame count), then each frame: one record, one wake-up
  std::vector<radio::Delivery> frames;
  frames.swap(ring->tick_radio);
  std::vector<uint8_t>& body = ring->tick_body;
  body.clear();  // (keeps its capacity: a flock's tick carries tens of kilobytes of frames)
  for (const radio::Delivery& d : frames) {
    shm::encode_radio_frame(static_cast<uint32_t>(d.to), static_cast<uint32_t>(d.from), d.seq,
                            d.broadcast, d.time_s, d.queued_s, d.data, &body);
  }
  const std::vector<uint8_t> head =
      shm::encode_tick_head(tick, time_s, static_cast<uint32_t>(frames.size()));
  const std::span<const uint8_t> parts[] = {head, body};
  // the tick ends the quiet that conn's done began: it wakes, with what was written meanwhile
  if (!ring->write_record(shm::RecordType::kTick, parts, /*ends_quiet=*/true))
    server_.close_overloaded(conn);
  return true;
}

void ShmTransport::hold_wakeups() { shared_->held.store(true); }

void ShmTransport::release_wakeups() {
  shared_->held.store(false);
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [conn, ring] : rings_) ring->release();
}

std::shared_ptr<ShmTransport::Ring> ShmTransport::ring_of(uint64_t conn) const {
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = rings_.find(conn);
  return it == rings_.end() ? nullptr : it->second;
}

void ShmTransport::quiet_until_tick(uint64_t conn) {
  if (const auto ring = ring_of(conn)) ring->set_quiet(true);
}

void ShmTransport::end_quiet(uint64_t conn) {
  if (const auto ring = ring_of(conn)) ring->set_quiet(false);
}

void ShmTransport::end_quiet_all() {
  std::lock_guard<std::mutex> lock(mutex_);
  for (auto& [conn, ring] : rings_) ring->set_quiet(false);
}

void ShmTransport::on_disconnect(uint64_t conn) {
  offered_.erase(conn);
  std::lock_guard<std::mutex> lock(mutex_);
  const auto it = rings_.find(conn);
  if (it == rings_.end()) return;
  it->second->set_quiet(false);  // what is written until the socket closes reaches the client
  rings_.erase(it);              // the LineServer lets go of its share when it closes the socket
}

}  // namespace uavsim::server::api
