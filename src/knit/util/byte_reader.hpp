#pragma once
// Bounds-checked little-endian reading of binary files for the importers. Every failure
// is a std::runtime_error of the form "<file>: <context> at byte <offset>: <message>".
#include <cstdint>
#include <cstring>
#include <stdexcept>
#include <string>
#include <string_view>

namespace knit::detail {

class ByteReader {
 public:
  ByteReader(std::string_view data, std::string name) : m_data(data), m_name(std::move(name)) {}

  /// Sets what is being read (e.g. "chunk 'yarn'"), named in error messages.
  void set_context(std::string context) { m_context = std::move(context); }
  size_t pos() const { return m_pos; }
  size_t size() const { return m_data.size(); }
  size_t remaining() const { return m_data.size() - m_pos; }
  void seek(size_t pos) {
    if (pos > m_data.size()) fail_at(m_pos, "offset beyond the end of the file");
    m_pos = pos;
  }

  template <class T>
  T get(const char* what) {
    need(sizeof(T), what);
    T value;
    std::memcpy(&value, m_data.data() + m_pos, sizeof(T));
    m_pos += sizeof(T);
    return value;
  }
  std::string_view bytes(size_t n, const char* what) {
    need(n, what);
    std::string_view s = m_data.substr(m_pos, n);
    m_pos += n;
    return s;
  }

  [[noreturn]] void fail(const std::string& msg) const { fail_at(m_pos, msg); }
  [[noreturn]] void fail_at(size_t offset, const std::string& msg) const {
    std::string text = m_name + ": ";
    if (!m_context.empty()) text += m_context + " ";
    text += "at byte " + std::to_string(offset) + ": " + msg;
    throw std::runtime_error(text);
  }

 private:
  void need(size_t n, const char* what) const {
    if (n > remaining())
      fail(std::string("file ends early while reading ") + what + " (needs " + std::to_string(n) +
           " bytes, " + std::to_string(remaining()) + " left; truncated?)");
  }
  std::string_view m_data;
  std::string m_name, m_context;
  size_t m_pos = 0;
};

/// Appends the bytes of a trivially copyable value (little-endian on our targets) to `out`,
/// the writing counterpart of ByteReader::get.
template <class T>
void put(std::string& out, T value) {
  char buf[sizeof(T)];
  std::memcpy(buf, &value, sizeof(T));
  out.append(buf, sizeof(T));
}

/// A 4-byte tag shown safely in messages: printable characters as is, others as `\xNN`.
inline std::string printable_tag(std::string_view tag) {
  std::string out;
  for (unsigned char c : tag) {
    if (c >= 32 && c < 127 && c != '\'') {
      out += static_cast<char>(c);
    } else {
      static const char* hex = "0123456789abcdef";
      out += "\\x";
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

}  // namespace knit::detail
