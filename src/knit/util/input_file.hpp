#pragma once
// Reading a whole input file with the checks every reader shares: the path must name a
// regular file (a directory, FIFO or device such as /dev/zero is refused by name), and
// its size must be within the reader's limit, checked before anything is read.
#include <cstddef>
#include <stdexcept>
#include <string>
#include <string_view>

namespace knit {

/// Input size limits (bytes), one per kind of file; a file over its limit is refused
/// before it is read.
inline constexpr std::size_t MAX_SCENE_BYTES = 64ull << 20;    ///< scene JSON
inline constexpr std::size_t MAX_CHART_BYTES = 1ull << 20;     ///< knit chart
inline constexpr std::size_t MAX_GEOMETRY_BYTES = 1ull << 30;  ///< .yarns/.bcc/.obj
inline constexpr std::size_t MAX_STATE_BYTES = 4ull << 30;     ///< .kstate
inline constexpr std::size_t MAX_CSV_BYTES = 1ull << 30;       ///< a CSV to plot

/// A file that is not there (read_input_file, check_input_path): the Python module raises
/// FileNotFoundError for it, the command line exits as for any refused input.
class FileNotFound : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// The contents of `path`, a regular file of at most `max_bytes`; `what` names the kind of
/// file in messages ("scene file", "chart", …). Throws std::runtime_error naming the path
/// and what is wrong (missing: FileNotFound; a directory, not a regular file, too large,
/// unreadable).
std::string read_input_file(const std::string& path, std::size_t max_bytes, const char* what);

/// The checks of read_input_file on the path alone (exists, not a directory, a regular
/// file), without reading it.
void check_input_path(const std::string& path, const char* what);

/// Memory available to a new allocation on this machine (bytes): MemAvailable of
/// /proc/meminfo, capped by the cgroup's limit where one is set; 0 when unknown.
double available_memory_bytes();

/// A byte count for messages: "512 B", "3.2 MB", "1.5 GB".
std::string format_bytes(double bytes);

/// `text` as a message may show it: bytes that do not print (control characters, binary
/// data, bytes beyond ASCII) as `\xNN`, and at most `max_bytes` of it, then "…".
std::string printable(std::string_view text, std::size_t max_bytes = 40);

/// A JSON library exception's text without the library's tag: "[json.exception.
/// type_error.302] type must be string, but is number" → "type must be string, but is
/// number", printable and at most 200 bytes.
std::string json_library_message(std::string_view what);

}  // namespace knit
