#include "uavsim/common/record_file.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <utility>

namespace uavsim::common {

namespace {

// all of bytes with write(2); errno set when false
bool write_all(int fd, std::string_view bytes) {
  while (!bytes.empty()) {
    const ssize_t n = ::write(fd, bytes.data(), bytes.size());
    if (n < 0) {
      if (errno == EINTR) continue;
      return false;
    }
    if (n == 0) {  // a regular file accepts at least one byte or says why; do not spin
      errno = EIO;
      return false;
    }
    bytes.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

std::string reason(const std::string& what, int err) { return what + ": " + std::strerror(err); }

}  // namespace

RecordFile::~RecordFile() { close(); }

RecordFile::RecordFile(RecordFile&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)),
      path_(std::move(other.path_)),
      error_(std::move(other.error_)),
      bytes_written_(other.bytes_written_) {}

RecordFile& RecordFile::operator=(RecordFile&& other) noexcept {
  if (this != &other) {
    close();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    error_ = std::move(other.error_);
    bytes_written_ = other.bytes_written_;
  }
  return *this;
}

bool RecordFile::open(const std::string& path, std::string* why) {
  close();
  path_ = path;
  error_.clear();
  bytes_written_ = 0;
  fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd_ < 0) {
    if (why != nullptr) *why = reason("cannot write " + path, errno);
    return false;
  }
  return true;
}

bool RecordFile::write(std::string_view bytes) {
  if (fd_ < 0 || !error_.empty()) return false;
  if (!write_all(fd_, bytes)) {
    error_ = reason(path_, errno);
    // a full disk (ENOSPC) or the file size limit (EFBIG) takes what fits and refuses the rest:
    // the part of this batch that got in is cut off again, so the file ends on a whole record
    // (shrinking needs no space)
    if (::ftruncate(fd_, static_cast<off_t>(bytes_written_)) == 0)
      (void)::lseek(fd_, static_cast<off_t>(bytes_written_), SEEK_SET);
    return false;
  }
  bytes_written_ += bytes.size();
  return true;
}

void RecordFile::close() {
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

bool replace_file_atomically(const std::string& path, std::string_view text, std::string* why) {
  const std::string tmp = path + ".tmp-" + std::to_string(::getpid());
  const int fd = ::open(tmp.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) {
    if (why != nullptr) *why = reason("cannot write " + tmp, errno);
    return false;
  }
  // the bytes on disk before the name points at them: a crash of the machine, not only of the
  // process, leaves the old file or the new one
  bool ok = write_all(fd, text) && ::fsync(fd) == 0;
  int err = errno;
  if (::close(fd) != 0 && ok) {
    ok = false;
    err = errno;
  }
  if (ok && ::rename(tmp.c_str(), path.c_str()) != 0) {
    ok = false;
    err = errno;
  }
  if (!ok) {
    ::unlink(tmp.c_str());
    if (why != nullptr) *why = reason("cannot write " + path, err);
    return false;
  }
  // the rename itself on disk
  const std::size_t slash = path.rfind('/');
  const std::string dir = slash == std::string::npos ? "."
                          : slash == 0               ? "/"
                                                     : path.substr(0, slash);
  if (const int dfd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC); dfd >= 0) {
    (void)::fsync(dfd);
    ::close(dfd);
  }
  return true;
}

}  // namespace uavsim::common
