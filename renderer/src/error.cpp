// Making exceptions and text that comes from files safe to print inside an error message.
#include "flashgs/error.h"

#include <new>

namespace flashgs {
namespace {

// Length of the valid UTF-8 sequence at `at` that is not a control character, or 0.
std::size_t printable_utf8_length(std::string_view text, std::size_t at) {
  const auto byte = [&](std::size_t i) { return static_cast<unsigned char>(text[i]); };
  const unsigned char lead = byte(at);
  std::size_t length = 0;
  if (lead >= 0xc2 && lead <= 0xdf) length = 2;
  else if (lead >= 0xe0 && lead <= 0xef) length = 3;
  else if (lead >= 0xf0 && lead <= 0xf4) length = 4;
  else return 0;
  if (at + length > text.size()) return 0;
  for (std::size_t i = 1; i < length; ++i)
    if ((byte(at + i) & 0xc0) != 0x80) return 0;
  const unsigned char second = byte(at + 1);
  if (lead == 0xc2 && second <= 0x9f) return 0;                 // C1 control characters
  if ((lead == 0xe0 && second < 0xa0) || (lead == 0xf0 && second < 0x90)) return 0;  // overlong
  if ((lead == 0xed && second > 0x9f) || (lead == 0xf4 && second > 0x8f)) return 0;  // surrogates, > U+10FFFF
  return length;
}

}  // namespace

std::string printable_file_text(std::string_view text, std::size_t max_bytes) {
  static const char kHex[] = "0123456789abcdef";
  std::string out;
  std::size_t i = 0;
  for (; i < text.size() && out.size() < max_bytes;) {
    const unsigned char c = static_cast<unsigned char>(text[i]);
    if (c >= 0x20 && c < 0x7f) {
      if (c == '\\' || c == '"') out += '\\';
      out += static_cast<char>(c);
      ++i;
    } else if (const std::size_t n = c >= 0x80 ? printable_utf8_length(text, i) : 0) {
      out.append(text.data() + i, n);
      i += n;
    } else {
      out += "\\x";
      out += kHex[c >> 4];
      out += kHex[c & 15];
      ++i;
    }
  }
  if (i < text.size()) out += "... (" + std::to_string(text.size()) + " bytes)";
  return out;
}

std::string printable_message(std::string_view message) {
  // Split at '"' and '\\', the only printable bytes printable_file_text changes; both are
  // ASCII, so no UTF-8 sequence is cut.
  std::string out;
  std::size_t begin = 0;
  for (std::size_t i = 0; i <= message.size(); ++i) {
    if (i < message.size() && message[i] != '"' && message[i] != '\\') continue;
    out += printable_file_text(message.substr(begin, i - begin), message.size() * 4 + 1);
    if (i < message.size()) out += message[i];
    begin = i + 1;
  }
  return out;
}

std::string error_text(const std::exception& e) {
  return dynamic_cast<const std::bad_alloc*>(&e) ? std::string("out of memory") : std::string(e.what());
}

}  // namespace flashgs
