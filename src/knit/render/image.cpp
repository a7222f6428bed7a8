// Image storage, PNG output (stb_image_write, compiled static into this file so it cannot
// clash with another copy) and labels drawn with stb_easy_font.
#include <algorithm>
#include <cmath>
#include <cstring>
#include <stdexcept>

#include "knit/io/state_file.hpp"
#include "knit/render/render.hpp"

#define STB_IMAGE_WRITE_STATIC
#define STB_IMAGE_WRITE_IMPLEMENTATION
#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#endif
#include <stb_easy_font.h>
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

namespace {
// stb_easy_font only knows printable ASCII
std::string printable(const std::string& text) {
  std::string s = text;
  for (char& c : s)
    if (c != '\n' && (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126))
      c = '?';
  return s;
}
}  // namespace

Eigen::Vector2i text_size(const std::string& text, int scale) {
  std::string s = printable(text);
  if (s.empty()) return {0, 0};
  return {stb_easy_font_width(s.data()) * scale, stb_easy_font_height(s.data()) * scale};
}

void draw_text(Image& image, int x0, int y0, const std::string& text, int scale,
               const Eigen::Vector3f& color) {
  std::string s = printable(text);
  if (s.empty()) return;
  std::vector<char> buffer(s.size() * 270 + 64);  // stb's estimate: ≤ ~270 bytes per char
  const int quads =
      stb_easy_font_print(0, 0, s.data(), nullptr, buffer.data(), static_cast<int>(buffer.size()));
  for (int q = 0; q < quads; ++q) {
    float xs[4], ys[4];
    for (int v = 0; v < 4; ++v) {
      std::memcpy(&xs[v], buffer.data() + q * 64 + v * 16, sizeof(float));
      std::memcpy(&ys[v], buffer.data() + q * 64 + v * 16 + 4, sizeof(float));
    }
    const int qx0 = x0 + static_cast<int>(std::lround(*std::min_element(xs, xs + 4) * scale));
    const int qx1 = x0 + static_cast<int>(std::lround(*std::max_element(xs, xs + 4) * scale));
    const int qy0 = y0 + static_cast<int>(std::lround(*std::min_element(ys, ys + 4) * scale));
    const int qy1 = y0 + static_cast<int>(std::lround(*std::max_element(ys, ys + 4) * scale));
    for (int y = std::max(qy0, 0); y < std::min(qy1, image.height); ++y)
      for (int x = std::max(qx0, 0); x < std::min(qx1, image.width); ++x)
        image.set_pixel(x, y, color);
  }
}

Image compose_side_by_side(const std::vector<Image>& images,
                           const std::vector<std::string>& labels) {
  if (images.empty()) throw std::invalid_argument("compose_side_by_side: no images");
  int height = 0, width = 0;
  for (const Image& im : images) {
    height = std::max(height, im.height);
    width += im.width;
  }
  const int scale = std::max(2, height / 160);
  bool any_label = false;
  for (const auto& l : labels) any_label |= !l.empty();
  const int strip = any_label ? text_size("Ag", scale).y() + 4 * scale : 0;
  const int gap = 4;
  width += gap * static_cast<int>(images.size() - 1);
  Image out(width, height + strip, Eigen::Vector3f::Ones());
  int x = 0;
  for (size_t i = 0; i < images.size(); ++i) {
    const Image& im = images[i];
    for (int y = 0; y < im.height; ++y)
      for (int c = 0; c < im.width; ++c) out.set_pixel(x + c, y, im.pixel(c, y));
    if (i < labels.size() && !labels[i].empty()) {
      const Eigen::Vector2i size = text_size(labels[i], scale);
      draw_text(out, x + (im.width - size.x()) / 2, height + 2 * scale, labels[i], scale,
                Eigen::Vector3f(0.15f, 0.15f, 0.15f));
    }
    x += im.width + gap;
  }
  return out;
}

}  // namespace knit
