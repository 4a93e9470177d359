#include "src/base/text.hpp"

#include <algorithm>
#include <charconv>
#include <cstdio>
#include <limits>

namespace knitsim {

std::string format_number(double value, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*g", digits, value);
  return buf;
}

void append_number(std::string& out, double value) {
  char buf[32];  // the longest shortest form, e.g. -2.2250738585072014e-308, has 24 characters
  out.append(buf, std::to_chars(buf, buf + sizeof buf, value).ptr);
}

void append_general(std::string& out, double value, int digits) {
  char buf[64];  // %.17g: at most 24 characters
  const auto end = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, digits);
  out.append(buf, end.ptr);
}

void append_integer(std::string& out, long long value) {
  char buf[24];
  out.append(buf, std::to_chars(buf, buf + sizeof buf, value).ptr);
}

std::string printable(const std::string& text) {
  std::string out;
  for (const char c : text) {
    const auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u != 0x7f) {
      out += c;
    } else {
      const char* hex = "0123456789abcdef";
      out += {'\\', 'x', hex[u >> 4], hex[u & 15]};
    }
  }
  return out;
}

namespace {

size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<size_t> row(b.size() + 1);
  for (size_t j = 0; j <= b.size(); ++j) row[j] = j;
  for (size_t i = 1; i <= a.size(); ++i) {
    size_t diagonal = row[0];
    row[0] = i;
    for (size_t j = 1; j <= b.size(); ++j) {
      const size_t up = row[j];
      row[j] = std::min({row[j] + 1, row[j - 1] + 1, diagonal + (a[i - 1] != b[j - 1] ? 1 : 0)});
      diagonal = up;
    }
  }
  return row[b.size()];
}

}  // namespace

std::string unknown_key_message(const std::string& key, const std::vector<std::string>& valid) {
  std::string best;
  size_t best_distance = std::numeric_limits<size_t>::max();
  for (const std::string& k : valid) {
    const size_t d = edit_distance(key, k);
    if (d < best_distance) best_distance = d, best = k;
  }
  std::string msg = printable(key) + ": unknown key; ";
  if (best_distance <= std::max<size_t>(3, key.size() / 3))
    return msg + "did you mean " + best + "?";
  msg += "valid keys:";
  for (const std::string& k : valid) msg += " " + k;
  return msg;
}

}  // namespace knitsim
