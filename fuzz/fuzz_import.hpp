#pragma once
// Shared body of the importer fuzz targets: parse, then fit what parsed. Any
// std::exception is a clean rejection; crashes, sanitizer reports and hangs are bugs.
#include <cstddef>
#include <cstdint>
#include <exception>
#include <string_view>

#include "knit/io/import.hpp"

namespace knit::fuzz {

template <class Parse>
int run(const uint8_t* data, size_t size, Parse parse, const char* name) {
  try {
    const auto raw = parse(std::string_view(reinterpret_cast<const char*>(data), size), name);
    ImportOptions opt;
    opt.max_segments = 300;  // keeps every iteration fast; larger yarns are rejected cleanly
    fit_yarns(raw, opt, name);
  } catch (const std::exception&) {
  }
  return 0;
}

}  // namespace knit::fuzz
