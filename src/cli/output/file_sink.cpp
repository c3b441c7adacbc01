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

bool FileSink::commit() {
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
  while (left > 0) {
    ssize_t n = ::write(fd_, p, left);
    if (n < 0) {
      if (errno == EINTR) continue;
      buffer_.clear();
      fail("cannot write");
    }
    p += n;
    left -= static_cast<std::size_t>(n);
    written_ += n;
  }
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
      fail("cannot write");
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
