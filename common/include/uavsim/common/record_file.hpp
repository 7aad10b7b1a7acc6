// Run logs that a SIGKILL cannot tear: a RecordFile hands each batch of whole records (text lines,
// tlog frames, CSV rows) to the kernel with write(2) at once, with no stdio or iostream buffer in
// between, so whatever the process had written when it is killed is on the file as whole records.
// The one residue the kernel allows: a write that spans a page boundary may be cut short there when
// a fatal signal arrives mid-copy, so a reader drops an unterminated last line or an incomplete
// last frame (read_tlog and the tests' readers do), never anything before it.
//
// replace_file_atomically() is the other half: a file rewritten whole (summary.json) is written
// beside its path, fsynced and renamed over it, so a kill at any moment leaves the old file or the
// new one, never a mix or an empty file.
#pragma once

#include <string>
#include <string_view>

namespace uavsim::common {

class RecordFile {
 public:
  RecordFile() = default;  // closed; write() fails until open()
  ~RecordFile();
  RecordFile(RecordFile&& other) noexcept;
  RecordFile& operator=(RecordFile&& other) noexcept;
  RecordFile(const RecordFile&) = delete;
  RecordFile& operator=(const RecordFile&) = delete;

  // Creates path (truncated), closing what was open. False with the reason ("cannot write PATH:
  // strerror") in *why (may be null). One thread at a time.
  bool open(const std::string& path, std::string* why);
  bool is_open() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }

  // Writes bytes, which must be whole records, with write(2) (retried after EINTR and short
  // writes). False when the file is not open or the kernel refused (ENOSPC, EFBIG, EIO, ...): what
  // this call got onto the file is cut off again (the file ends on the records of the calls that
  // succeeded), the first failure's text stays in error() and every later write is refused too,
  // so a full disk costs one message, not one per record.
  // One thread at a time.
  bool write(std::string_view bytes);
  // "" until a write failed; then "PATH: strerror".
  const std::string& error() const { return error_; }
  // Bytes written so far.
  std::size_t bytes_written() const { return bytes_written_; }

  void close();

 private:
  int fd_ = -1;
  std::string path_;
  std::string error_;
  std::size_t bytes_written_ = 0;
};

// Replaces path by text atomically: PATH.tmp-PID written, fsynced, renamed over path, its directory
// fsynced. A reader (or a kill) at any moment sees the previous file or the new one, whole. False
// with the reason in *why (may be null); the temporary file is removed then. Thread-safe (different
// paths; the temporary's name has the process id, so one writer per path and process).
bool replace_file_atomically(const std::string& path, std::string_view text, std::string* why);

}  // namespace uavsim::common
