#include "knit/util/input_file.hpp"

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <system_error>

namespace knit {

std::string format_bytes(double bytes) {
  char buf[32];
  if (bytes < 1024)
    std::snprintf(buf, sizeof buf, "%.0f B", bytes);
  else if (bytes < 1024.0 * 1024)
    std::snprintf(buf, sizeof buf, "%.1f kB", bytes / 1024);
  else if (bytes < 1024.0 * 1024 * 1024)
    std::snprintf(buf, sizeof buf, "%.1f MB", bytes / (1024.0 * 1024));
  else
    std::snprintf(buf, sizeof buf, "%.1f GB", bytes / (1024.0 * 1024 * 1024));
  return buf;
}

std::string printable(std::string_view text, std::size_t max_bytes) {
  std::string out;
  const std::size_t n = std::min(text.size(), max_bytes);
  for (std::size_t k = 0; k < n; ++k) {
    const auto c = static_cast<unsigned char>(text[k]);
    if (c >= 0x20 && c < 0x7f) {
      out += static_cast<char>(c);
    } else {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\x%02X", c);
      out += buf;
    }
  }
  if (text.size() > max_bytes) out += "…";
  return out;
}

std::string json_library_message(std::string_view what) {
  if (what.substr(0, 16) == "[json.exception." && what.find("] ") != std::string_view::npos)
    what.remove_prefix(what.find("] ") + 2);
  return printable(what, 200);
}

double available_memory_bytes() {
  double avail = 0;
  {
    std::ifstream in("/proc/meminfo");
    std::string key;
    double value;
    std::string unit;
    while (in >> key >> value) {
      std::getline(in, unit);
      if (key == "MemAvailable:") {
        avail = value * 1024;
        break;
      }
    }
  }
  // a container's limit (cgroup v2, then v1)
  for (const char* path :
       {"/sys/fs/cgroup/memory.max", "/sys/fs/cgroup/memory/memory.limit_in_bytes"}) {
    std::ifstream in(path);
    std::string text;
    if (!(in >> text) || text == "max") continue;
    const double limit = std::strtod(text.c_str(), nullptr);
    if (limit > 0 && limit < 1e18 && (avail == 0 || limit < avail)) avail = limit;
  }
  return avail;
}

void check_input_path(const std::string& path, const char* what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  const fs::file_status st = fs::status(path, ec);
  if (ec || !fs::exists(st)) throw FileNotFound(path + ": cannot open " + what + " (no such file)");
  if (fs::is_directory(st))
    throw std::runtime_error(path + ": is a directory; expected a " + std::string(what));
  if (!fs::is_regular_file(st))
    throw std::runtime_error(path + ": is not a regular file (a device, FIFO or socket); " +
                             "expected a " + what);
}

std::string read_input_file(const std::string& path, std::size_t max_bytes, const char* what) {
  namespace fs = std::filesystem;
  std::error_code ec;
  check_input_path(path, what);
  const auto size = fs::file_size(path, ec);
  if (ec) throw std::runtime_error(path + ": cannot read " + what + ": " + ec.message());
  if (size > max_bytes)
    throw std::runtime_error(path + ": " + format_bytes(static_cast<double>(size)) +
                             ", more than the " + format_bytes(static_cast<double>(max_bytes)) +
                             " a " + what + " may be");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw std::runtime_error(path + ": cannot open " + what + " for reading");
  std::string data(static_cast<std::size_t>(size), '\0');
  in.read(data.data(), static_cast<std::streamsize>(size));
  if (in.gcount() != static_cast<std::streamsize>(size) || in.bad())
    throw std::runtime_error(path + ": read failed (the " + what + " changed while being read?)");
  return data;
}

}  // namespace knit
