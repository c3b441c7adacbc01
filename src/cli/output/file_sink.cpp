#include "file_sink.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

#include <fcntl.h>
#include <time.h>
#include <unistd.h>

namespace padsim::output::detail {

namespace {
constexpr std::size_t flush_bytes = 1 << 16;                 // 64 KiB
// A record committed 0.1 s or more after the previous flush is written at once: rows that come
// slowly reach the file one by one, fast ones in 64 KiB blocks at least ten times a second.
constexpr auto flush_interval = std::chrono::milliseconds(100);

// The monotonic clock at its tick (a few ms, far below the flush interval): it is read once per
// record, and the precise clock took 3 % of writing buck_1000 on the TSTEP grid (200,000 rows).
std::chrono::nanoseconds coarse_now() {
  timespec now{};
  ::clock_gettime(CLOCK_MONOTONIC_COARSE, &now);
  return std::chrono::seconds(now.tv_sec) + std::chrono::nanoseconds(now.tv_nsec);
}
}  // namespace

FileSink::FileSink(const std::string& path) : path_(path) {
  if (path == "-") {
    fd_ = STDOUT_FILENO;
  } else {
    fd_ = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (fd_ < 0) fail("cannot open");
    owns_fd_ = true;
  }
  last_flush_ = coarse_now();
}

FileSink::~FileSink() {
  try {
    close();
  } catch (...) {
  }
}

void FileSink::fail(const char* what) {
  failed_ = true;
  throw std::runtime_error(fmt::format("{} '{}': {}", what, path_, std::strerror(errno)));
}

void FileSink::fail_write(std::int64_t flushed) {
  const int reason = errno;
  failed_ = true;
  buffer_.clear();
  // The failed flush's bytes that reached the file (the last record in part, after a short
  // write) are cut back off: at the file's offset less them, which is also right for a file
  // opened for appending (standard output, >>). A pipe cannot be cut.
  bool partial_tail = false;
  if (flushed > 0) {
    const off_t end = ::lseek(fd_, 0, SEEK_CUR);
    partial_tail = !(end >= flushed && ::ftruncate(fd_, end - flushed) == 0);
  }
  throw WriteError(fmt::format("cannot write '{}': {}", path_, std::strerror(reason)), path_, last_time_on_disk_,
                   partial_tail);
}

bool FileSink::commit(double t) {
  last_time_ = t;
  if (buffer_.size() >= flush_bytes) {
    flush();
    return true;
  }
  if (coarse_now() - last_flush_ >= flush_interval) {
    flush();
    return true;
  }
  return false;
}

void FileSink::flush() {
  if (fd_ < 0) {
    buffer_.clear();
    return;
  }
  const char* p = buffer_.data();
  std::size_t left = buffer_.size();
  std::int64_t flushed = 0;
  while (left > 0) {
    ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_write(flushed);
    }
    p += n;
    left -= static_cast<std::size_t>(n);
    flushed += n;
  }
  written_ += flushed;
  last_time_on_disk_ = last_time_;
  buffer_.clear();
  last_flush_ = coarse_now();
}

void FileSink::pwrite_at(std::int64_t offset, std::string_view bytes) {
  if (fd_ < 0) return;
  std::size_t done = 0;
  while (done < bytes.size()) {
    ssize_t n = ::pwrite(fd_, bytes.data() + done, bytes.size() - done,
                         static_cast<off_t>(offset + static_cast<std::int64_t>(done)));
    if (n < 0) {
      if (errno == EINTR) continue;
      fail_write(0);
    }
    done += static_cast<std::size_t>(n);
  }
}

void FileSink::close() {
  if (fd_ < 0) return;
  if (failed_) {
    buffer_.clear();
  } else {
    try {
      flush();
    } catch (...) {
      if (owns_fd_) ::close(fd_);
      fd_ = -1;
      throw;
    }
  }
  int fd = fd_;
  fd_ = -1;
  if (owns_fd_ && ::close(fd) != 0 && !failed_) fail("cannot close");
}

}  // namespace padsim::output::detail
