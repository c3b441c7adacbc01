// PNG plot of a padsim CSV through gnuplot (pngcairo when present, else png).
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

#include <fmt/format.h>

#include "cli/output/waveform_writer.hpp"

namespace padsim::output {

namespace {

// Appends formatted text to a buffer.
template <typename Buffer, typename... Args>
void put(Buffer& out, fmt::format_string<Args...> format, Args&&... args) {
  fmt::format_to(std::back_inserter(out), format, std::forward<Args>(args)...);
}

// Splits the CSV header, honouring double-quoted fields.
std::vector<std::string> split_header(const std::string& line) {
  std::vector<std::string> fields(1);
  bool quoted = false;
  for (std::size_t k = 0; k < line.size(); ++k) {
    char c = line[k];
    if (quoted) {
      if (c == '"' && k + 1 < line.size() && line[k + 1] == '"') {
        fields.back() += '"';
        ++k;
      } else if (c == '"') {
        quoted = false;
      } else {
        fields.back() += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields.emplace_back();
    } else if (c != '\r') {
      fields.back() += c;
    }
  }
  return fields;
}

// Last time value in the file (first field of the last non-empty line).
bool last_time(const std::string& path, double& t) {
  std::ifstream in(path, std::ios::binary | std::ios::ate);
  if (!in) return false;
  std::streamoff size = in.tellg();
  std::streamoff start = size > 4096 ? size - 4096 : 0;
  in.seekg(start);
  std::string tail((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!tail.empty() && (tail.back() == '\n' || tail.back() == '\r')) tail.pop_back();
  auto nl = tail.rfind('\n');
  std::string last = nl == std::string::npos ? tail : tail.substr(nl + 1);
  char* end = nullptr;
  t = std::strtod(last.c_str(), &end);
  return end != last.c_str();
}

// A gnuplot single-quoted string literal.
std::string quote(const std::string& s) {
  std::string out = "'";
  for (char c : s) {
    if (c == '\'') out += "''";
    else if (c != '\n' && c != '\r') out += c;
  }
  return out + "'";
}

struct Panel {
  std::string ylabel;
  std::vector<std::size_t> columns;  // 1-based CSV column numbers (time is 1)
};

// A file of our own in /tmp, removed when this goes out of scope.
class TemporaryFile {
 public:
  // `suffix` after the unique part (gnuplot takes the format from the terminal, not the name).
  explicit TemporaryFile(const std::string& suffix) : path_("/tmp/padsim-plot-XXXXXX" + suffix) {
    const int fd = ::mkstemps(path_.data(), static_cast<int>(suffix.size()));
    if (fd < 0) path_.clear();
    else ::close(fd);
  }
  ~TemporaryFile() {
    if (!path_.empty()) ::unlink(path_.c_str());
  }
  TemporaryFile(const TemporaryFile&) = delete;
  TemporaryFile& operator=(const TemporaryFile&) = delete;
  bool created() const { return !path_.empty(); }
  const std::string& path() const { return path_; }

 private:
  std::string path_;
};

}  // namespace

bool plot_png(const std::string& csv_path, const std::string& png_path, const std::string& note, std::string& error) {
  std::ifstream in(csv_path);
  if (!in) {
    error = fmt::format("cannot read '{}'", csv_path);
    return false;
  }
  std::string header;
  std::getline(in, header);
  auto names = split_header(header);
  if (names.size() < 2 || names[0] != "time") {
    error = fmt::format("'{}' is not a padsim CSV (header must start with time and one signal)", csv_path);
    return false;
  }
  std::string second;
  if (!std::getline(in, second)) {
    error = fmt::format("'{}' has no data rows", csv_path);
    return false;
  }
  in.close();

  // Time axis unit.
  double tend = 0;
  last_time(csv_path, tend);
  struct Unit { double scale; const char* name; };
  Unit unit{1, "s"};
  double at = std::fabs(tend);
  if (at > 0 && at < 1e-6) unit = {1e9, "ns"};
  else if (at > 0 && at < 1e-3) unit = {1e6, "us"};
  else if (at > 0 && at < 1) unit = {1e3, "ms"};

  // Panels: one per signal up to six signals, else one for voltages and one for currents.
  std::vector<Panel> panels;
  const std::size_t signals = names.size() - 1;
  auto is_current = [](const std::string& n) {
    return n.size() > 2 && (n[0] == 'i' || n[0] == 'I') && n[1] == '(';
  };
  if (signals <= 6) {
    for (std::size_t k = 1; k <= signals; ++k)
      panels.push_back({is_current(names[k]) ? "current (A)" : "voltage (V)", {k + 1}});
  } else {
    Panel v{"voltage (V)", {}}, i{"current (A)", {}};
    for (std::size_t k = 1; k <= signals; ++k) (is_current(names[k]) ? i : v).columns.push_back(k + 1);
    if (!v.columns.empty()) panels.push_back(v);
    if (!i.columns.empty()) panels.push_back(i);
  }

  const int width = 1000;
  const int panel_height = panels.size() == 1 ? 500 : 260;
  const int height = panel_height * static_cast<int>(panels.size()) + 40;
  std::string script;
  put(script, "if (strstrt(GPVAL_TERMINALS, 'pngcairo') > 0) {{\n"
      "  set terminal pngcairo size {0},{1} font 'sans,10' noenhanced\n"
      "}} else {{\n"
      "  set terminal png size {0},{1} noenhanced\n"
      "}}\n", width, height);
  // gnuplot writes a file of our own, copied to png_path once it is a PNG: the user's path is
  // opened for writing as -o opens it (through a symlink, onto a device), never removed first.
  const TemporaryFile png_written(".png");
  if (!png_written.created()) {
    error = "cannot create a temporary file for gnuplot's PNG";
    return false;
  }
  put(script, "set output {}\n", quote(png_written.path()));
  put(script, "set datafile separator ','\n");
  put(script, "set grid\nset key top right noenhanced\nset lmargin 12\nset rmargin 4\n");
  const std::string title = std::filesystem::path(csv_path).filename().string();
  put(script, "set multiplot layout {},1 title {} noenhanced\n", panels.size(), quote(note.empty() ? title : title + " (" + note + ")"));
  for (std::size_t p = 0; p < panels.size(); ++p) {
    const auto& panel = panels[p];
    put(script, "set ylabel {}\n", quote(panel.ylabel));
    if (p + 1 == panels.size()) put(script, "set xlabel {}\n", quote(fmt::format("time ({})", unit.name)));
    else put(script, "unset xlabel\n");
    put(script, "plot ");
    for (std::size_t k = 0; k < panel.columns.size(); ++k) {
      std::size_t c = panel.columns[k];
      put(script, "{}{} using ($1*{}):{} skip 1 with lines lw 1.5 lc {} title {}",
          k ? ", " : "", quote(csv_path), unit.scale, c, c - 1, quote(names[c - 1]));
    }
    put(script, "\n");
  }
  put(script, "unset multiplot\nset output\n");

  const TemporaryFile script_file("");
  std::ofstream script_out;
  if (script_file.created()) script_out.open(script_file.path(), std::ios::binary);
  if (!script_out || !(script_out << script) || !script_out.flush()) {
    error = "cannot write the temporary gnuplot script";
    return false;
  }
  script_out.close();
  std::string command = fmt::format("gnuplot {} 2>&1", script_file.path());  // mkstemps path: no quoting needed
  FILE* pipe = ::popen(command.c_str(), "r");
  if (!pipe) {
    error = "cannot start gnuplot";
    return false;
  }
  std::string messages;
  std::array<char, 512> chunk;
  while (std::size_t n = std::fread(chunk.data(), 1, chunk.size(), pipe)) messages.append(chunk.data(), n);
  int status = ::pclose(pipe);
  if (status == -1 || !WIFEXITED(status) || WEXITSTATUS(status) != 0) {
    if (WIFEXITED(status) && WEXITSTATUS(status) == 127)
      error = "gnuplot not found (install gnuplot-nox)";
    else
      error = fmt::format("gnuplot failed: {}", messages.empty() ? "no message" : messages);
    return false;
  }
  // gnuplot reports some errors (missing columns, unreadable file) without a failing exit code.
  std::ifstream png(png_written.path(), std::ios::binary);
  char magic[8] = {};
  if (!png.read(magic, 8) || std::string_view(magic, 8) != std::string_view("\x89PNG\r\n\x1a\n", 8)) {
    error = fmt::format("gnuplot did not write a PNG for '{}'{}{}", png_path,
                        messages.empty() ? "" : ": ", messages);
    return false;
  }
  png.seekg(0);
  std::ofstream out(png_path, std::ios::binary | std::ios::trunc);
  if (!out || !(out << png.rdbuf()) || !out.flush()) {
    error = fmt::format("cannot write '{}': {}", png_path, std::strerror(errno));
    return false;
  }
  return true;
}

}  // namespace padsim::output
