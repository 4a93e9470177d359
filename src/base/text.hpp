// Text for people: numbers as short or lossless decimals, input echoed safely in one-line
// messages, and the "unknown key" message with its nearest valid key.
#pragma once

#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace knitsim {

// printf %.<digits>g (lossless for doubles at digits = 17).
std::string format_number(double value, int digits = 4);
// Appends the shortest decimal text that reads back as exactly `value` (std::to_chars; several
// times faster than a stream at precision 17, for large CSV and VTK files).
void append_number(std::string& out, double value);
// Appends printf's %.<digits>g text of `value` (std::to_chars in general format, which the
// standard defines as printf's: the same characters, without a stream's or printf's overhead).
void append_general(std::string& out, double value, int digits);
// Appends an integer in decimal.
void append_integer(std::string& out, long long value);

// `text` as it may appear in a one-line message: control bytes (newline, tab, ...) and DEL as
// \xNN, everything else unchanged.
std::string printable(const std::string& text);

// The message for a key that is not in `valid` (KEY shown printable()): "KEY: unknown key; did you
// mean NEAREST?" when the nearest valid key is within max(3, |KEY| / 3) edits (Levenshtein), else
// "KEY: unknown key; valid keys: K1 K2 ...".
std::string unknown_key_message(const std::string& key, const std::vector<std::string>& valid);

}  // namespace knitsim
