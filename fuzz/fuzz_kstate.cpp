// libFuzzer target: the .kstate reader. read_state_file takes a path, so each input is
// written to a file private to this process first.
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

#include "knit/io/state_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  // the input's file, removed when the fuzzer exits
  static const struct TempFile {
    std::string path = (std::filesystem::temp_directory_path() /
                        ("knit-fuzz-" + std::to_string(getpid()) + ".kstate"))
                           .string();
    ~TempFile() {
      std::error_code ec;
      std::filesystem::remove(path, ec);
    }
  } temp;
  const std::string& path = temp.path;
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    knit::read_state_file(path);
  } catch (const std::exception&) {
  }
  return 0;
}
