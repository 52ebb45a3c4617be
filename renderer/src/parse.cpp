// Strict parsers of user-typed values (see parse.h).
#include "flashgs/parse.h"

#include <cstdint>

#include "flashgs/error.h"

namespace flashgs {
namespace {

// Reads the decimal digits at text[*pos...]; false when there are none or the value exceeds
// `limit` (checked digit by digit, so nothing overflows).
bool read_bounded(const std::string& text, std::size_t* pos, std::int64_t limit, int* value) {
  std::int64_t v = 0;
  const std::size_t start = *pos;
  for (; *pos < text.size() && text[*pos] >= '0' && text[*pos] <= '9'; ++*pos) {
    v = v * 10 + (text[*pos] - '0');
    if (v > limit) return false;
  }
  if (*pos == start) return false;
  *value = static_cast<int>(v);
  return true;
}

}  // namespace

Resolution parse_resolution(const std::string& text, int max_side) {
  Resolution r;
  std::size_t pos = 0;
  bool ok = read_bounded(text, &pos, max_side, &r.width) && pos < text.size() && (text[pos] == 'x' || text[pos] == 'X');
  ++pos;
  ok = ok && read_bounded(text, &pos, max_side, &r.height) && pos == text.size() && r.width >= 1 && r.height >= 1;
  if (!ok)
    throw Error("resolution \"" + text + "\": expected WxH with 1 <= W, H <= " + std::to_string(max_side));
  return r;
}

}  // namespace flashgs
