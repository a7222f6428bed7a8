// Image storage, PNG output (stb_image_write, compiled static into this file so it cannot
// clash with another copy) and side-by-side panels with labels (text.cpp draws them).
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "knit/io/state_file.hpp"
#include "knit/present/render.hpp"
#include "knit/util/atomic_file.hpp"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#endif
#include <stb_image_write.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace knit {

Image::Image(int w, int h, Eigen::Vector3f fill) : width(w), height(h) {
  if (w <= 0 || h <= 0) throw std::invalid_argument("image size must be positive");
  rgb.resize(3 * static_cast<size_t>(w) * h);
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) set_pixel(x, y, fill);
}

Eigen::Vector3f Image::pixel(int x, int y) const {
  const size_t i = 3 * (static_cast<size_t>(y) * width + x);
  return Eigen::Vector3f(rgb[i], rgb[i + 1], rgb[i + 2]) / 255.0f;
}

void Image::set_pixel(int x, int y, const Eigen::Vector3f& c) {
  const size_t i = 3 * (static_cast<size_t>(y) * width + x);
  for (int k = 0; k < 3; ++k)
    rgb[i + k] = static_cast<uint8_t>(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255.0f));
}

void write_png(const Image& image, const std::string& path) {
  if (image.width <= 0 || image.height <= 0 ||
      image.rgb.size() != 3 * static_cast<size_t>(image.width) * image.height)
    throw std::invalid_argument(path + ": cannot write an empty or malformed image");
  std::string bytes;
  auto sink = [](void* context, void* data, int size) {
    static_cast<std::string*>(context)->append(static_cast<const char*>(data), size);
  };
  if (!stbi_write_png_to_func(sink, &bytes, image.width, image.height, 3, image.rgb.data(),
                              3 * image.width))
    throw std::runtime_error(path + ": PNG encoding failed");
  write_file_atomic(path, bytes);
}

Image compose_side_by_side(const std::vector<Image>& images,
                           const std::vector<std::string>& labels) {
  if (images.empty()) throw std::invalid_argument("compose_side_by_side: no images");
  int height = 0, width = 0;
  for (const Image& im : images) {
    height = std::max(height, im.height);
    width += im.width;
  }
  const int px = std::max(14, height / 18);  // label height, pixels
  bool any_label = false;
  for (const auto& l : labels) any_label |= !l.empty();
  const int strip = any_label ? text_size("Ag", px).y() + px / 2 : 0;
  const int gap = 4;
  width += gap * static_cast<int>(images.size() - 1);
  Image out(width, height + strip, Eigen::Vector3f::Ones());
  int x = 0;
  for (size_t i = 0; i < images.size(); ++i) {
    const Image& im = images[i];
    for (int y = 0; y < im.height; ++y)
      for (int c = 0; c < im.width; ++c) out.set_pixel(x + c, y, im.pixel(c, y));
    if (i < labels.size() && !labels[i].empty()) {
      const Eigen::Vector2i size = text_size(labels[i], px);
      draw_text(out, x + (im.width - size.x()) / 2, height + px / 4, labels[i], px,
                Eigen::Vector3f(0.15f, 0.15f, 0.15f));
    }
    x += im.width + gap;
  }
  return out;
}

}  // namespace knit
