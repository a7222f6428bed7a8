// Labels on images: UTF-8 text drawn anti-aliased with FreeType from a TrueType font
// (DejaVu Sans), with stb_easy_font's bitmap glyphs as the fallback where no font is found.
#include <ft2build.h>
#include FT_FREETYPE_H

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <mutex>
#include <string>
#include <vector>

#include "knit/present/render.hpp"

#if defined(__GNUC__)
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wmissing-field-initializers"
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic ignored "-Wsign-compare"
#endif
#include <stb_easy_font.h>
#if defined(__GNUC__)
#pragma GCC diagnostic pop
#endif

namespace knit {
namespace {

// Debian's fonts-dejavu-core (and where other systems keep DejaVu)
constexpr const char* FONT_CANDIDATES[] = {
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/TTF/DejaVuSans.ttf",
    "/usr/share/fonts/dejavu/DejaVuSans.ttf",
};

// One FreeType face shared by every caller; FreeType objects are not thread-safe, so
// every use holds `mutex`.
struct Font {
  std::mutex mutex;
  FT_Library library = nullptr;
  FT_Face face = nullptr;
  std::string path;

  Font() {
    std::vector<std::string> paths;
    if (const char* env = std::getenv("KNIT_FONT"); env != nullptr && *env != '\0')
      paths.emplace_back(env);
    for (const char* c : FONT_CANDIDATES) paths.emplace_back(c);
    if (FT_Init_FreeType(&library) != 0) {
      library = nullptr;
      std::fprintf(stderr,
                   "knitsim: warning: FreeType failed to start; labels use a bitmap font\n");
      return;
    }
    for (const std::string& p : paths) {
      std::error_code ec;
      if (!std::filesystem::is_regular_file(p, ec)) continue;
      if (FT_New_Face(library, p.c_str(), 0, &face) == 0) {
        path = p;
        return;
      }
      face = nullptr;
    }
    std::fprintf(stderr,
                 "knitsim: warning: no TrueType font found (install Debian's fonts-dejavu-core "
                 "or set KNIT_FONT); labels use a bitmap font\n");
  }
  ~Font() {
    if (face != nullptr) FT_Done_Face(face);
    if (library != nullptr) FT_Done_FreeType(library);
  }
};

Font& font() {
  static Font f;
  return f;
}

// UTF-8 to code points; a malformed byte becomes U+FFFD
std::vector<char32_t> decode_utf8(const std::string& s) {
  std::vector<char32_t> out;
  for (size_t i = 0; i < s.size();) {
    const auto b = static_cast<unsigned char>(s[i]);
    int n = b < 0x80 ? 0 : (b >> 5) == 6 ? 1 : (b >> 4) == 14 ? 2 : (b >> 3) == 30 ? 3 : -1;
    char32_t cp = n == 0 ? b : n == 1 ? (b & 0x1f) : n == 2 ? (b & 0x0f) : (b & 0x07);
    bool ok = n >= 0 && i + n < s.size();
    for (int k = 1; ok && k <= n; ++k) {
      const auto c = static_cast<unsigned char>(s[i + k]);
      ok = (c >> 6) == 2;
      cp = (cp << 6) | (c & 0x3f);
    }
    if (!ok) {
      out.push_back(0xfffd);
      ++i;
      continue;
    }
    out.push_back(cp);
    i += n + 1;
  }
  return out;
}

// Lays out (and with `image`, draws) the text; returns its width and height in pixels.
// Callers hold font().mutex.
Eigen::Vector2i layout(Font& f, Image* image, int x0, int y0, const std::string& text,
                       int pixel_height, const Eigen::Vector3f& color) {
  FT_Face face = f.face;
  // the line is pixel_height tall: size the em so ascender − descender fills it
  const double line_units = static_cast<double>(face->ascender - face->descender);
  const auto em = static_cast<FT_UInt>(
      std::max(1.0, std::round(pixel_height * face->units_per_EM / line_units)));
  FT_Set_Pixel_Sizes(face, 0, em);
  const int ascender = static_cast<int>(face->size->metrics.ascender >> 6);
  const int line = pixel_height;
  int width = 0, pen_x = 0, lines = 1;
  FT_UInt previous = 0;
  for (char32_t cp : decode_utf8(text)) {
    if (cp == U'\n') {
      width = std::max(width, pen_x);
      pen_x = 0;
      ++lines;
      previous = 0;
      continue;
    }
    FT_UInt glyph = FT_Get_Char_Index(face, cp);
    if (glyph == 0) glyph = FT_Get_Char_Index(face, U'?');
    if (previous != 0 && glyph != 0 && FT_HAS_KERNING(face)) {
      FT_Vector kern;
      if (FT_Get_Kerning(face, previous, glyph, FT_KERNING_DEFAULT, &kern) == 0)
        pen_x += static_cast<int>(kern.x >> 6);
    }
    previous = glyph;
    if (FT_Load_Glyph(face, glyph, image != nullptr ? FT_LOAD_RENDER : FT_LOAD_DEFAULT) != 0)
      continue;
    const FT_GlyphSlot g = face->glyph;
    if (image != nullptr) {
      const FT_Bitmap& bm = g->bitmap;
      const int gx = x0 + pen_x + g->bitmap_left;
      const int gy = y0 + (lines - 1) * line + ascender - g->bitmap_top;
      for (unsigned r = 0; r < bm.rows; ++r) {
        const int y = gy + static_cast<int>(r);
        if (y < 0 || y >= image->height) continue;
        for (unsigned c = 0; c < bm.width; ++c) {
          const int x = gx + static_cast<int>(c);
          if (x < 0 || x >= image->width) continue;
          const float a = bm.buffer[r * bm.pitch + c] / 255.0f;
          if (a <= 0) continue;
          image->set_pixel(x, y, (1 - a) * image->pixel(x, y) + a * color);
        }
      }
    }
    pen_x += static_cast<int>(g->advance.x >> 6);
  }
  width = std::max(width, pen_x);
  if (width == 0 && lines == 1) return {0, 0};
  return {width, lines * line};
}

// stb_easy_font only knows printable ASCII
std::string printable(const std::string& text) {
  std::string s = text;
  for (char& c : s)
    if (c != '\n' && (static_cast<unsigned char>(c) < 32 || static_cast<unsigned char>(c) > 126))
      c = '?';
  return s;
}

// the bitmap font's glyphs are 12 pixels a line at scale 1
int bitmap_scale(int pixel_height) {
  return std::max(1, (pixel_height + 6) / 12);
}

}  // namespace

std::string label_font_path() {
  Font& f = font();
  std::lock_guard<std::mutex> lock(f.mutex);
  return f.face != nullptr ? f.path : std::string();
}

Eigen::Vector2i text_size(const std::string& text, int pixel_height) {
  if (text.empty() || pixel_height <= 0) return {0, 0};
  Font& f = font();
  {
    std::lock_guard<std::mutex> lock(f.mutex);
    if (f.face != nullptr)
      return layout(f, nullptr, 0, 0, text, pixel_height, Eigen::Vector3f::Zero());
  }
  std::string s = printable(text);
  const int scale = bitmap_scale(pixel_height);
  return {stb_easy_font_width(s.data()) * scale, stb_easy_font_height(s.data()) * scale};
}

void draw_text(Image& image, int x0, int y0, const std::string& text, int pixel_height,
               const Eigen::Vector3f& color) {
  if (text.empty() || pixel_height <= 0) return;
  Font& f = font();
  {
    std::lock_guard<std::mutex> lock(f.mutex);
    if (f.face != nullptr) {
      layout(f, &image, x0, y0, text, pixel_height, color);
      return;
    }
  }
  std::string s = printable(text);
  const int scale = bitmap_scale(pixel_height);
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

}  // namespace knit
