// Internal: an unbuffered file descriptor fed whole records from a user-space buffer.
// Records (CSV lines, raw points, event lines) are appended with commit(); the buffer reaches the
// file only at record boundaries: when it grows past 64 KiB, or when a record is committed 0.1 s
// or more after the previous flush (so a row that arrives slowly is written at once). A flush
// that fails (disk full, file-size limit) is cut back off the file, which then ends at the last
// record of the flush before: the WriteError says at which record's time.
#pragma once

#include <chrono>
#include <cstdint>
#include <optional>
#include <string>
#include <string_view>

#include <fmt/format.h>

#include "cli/output/waveform_writer.hpp"

namespace padsim::output::detail {

class FileSink {
 public:
  // path "-" is standard output (not closed at the end).
  explicit FileSink(const std::string& path);
  ~FileSink();
  FileSink(const FileSink&) = delete;
  FileSink& operator=(const FileSink&) = delete;

  fmt::memory_buffer& buffer() { return buffer_; }  // append one record, then commit()
  // Marks the end of a record of time t; returns true when the buffer was written to the file.
  bool commit(double t);
  void flush();                                     // writes the buffer now
  std::int64_t offset() const { return written_; }  // bytes in the file so far (after flush)
  void pwrite_at(std::int64_t offset, std::string_view bytes);  // overwrite in place
  void close();                                     // flush and close; idempotent, no throw after failure
  const std::string& path() const { return path_; }
  bool failed() const { return failed_; }

 private:
  [[noreturn]] void fail(const char* what);
  [[noreturn]] void fail_write(std::int64_t flushed);
  std::string path_;
  int fd_ = -1;
  bool owns_fd_ = false;
  bool failed_ = false;
  std::int64_t written_ = 0;
  std::optional<double> last_time_, last_time_on_disk_;  // of the records committed, flushed
  fmt::memory_buffer buffer_;
  std::chrono::nanoseconds last_flush_{};  // on the coarse monotonic clock (file_sink.cpp)
};

}  // namespace padsim::output::detail
