// Bad input that names one field: the one message format of every validate() and of the scene
// keys, "FIELD = VALUE: ACCEPTED", e.g. "knit.contact = 120: must be in [0, 100]".
//
//   if (!(rtol > 0.0 && rtol < 1.0)) bad_field("rtol", rtol, "must be in (0, 1)");
//
// The exception keeps the three parts, so a caller that knows what the user typed (a scene key,
// a command-line flag, the value's own text) can say it in the user's words (src/scene/).
#pragma once

#include <sstream>
#include <stdexcept>
#include <string>

namespace knitsim {

class InvalidField : public std::invalid_argument {
 public:
  InvalidField(const std::string& field, const std::string& value, const std::string& accepted)
      : std::invalid_argument(field + " = " + value + ": " + accepted),
        field_(field),
        value_(value),
        accepted_(accepted) {}
  const std::string& field() const { return field_; }        // as the validator names it
  const std::string& value() const { return value_; }        // as text
  const std::string& accepted() const { return accepted_; }  // "must be ..."

 private:
  std::string field_, value_, accepted_;
};

// Throws InvalidField with `value` as a default std::ostream prints it (6 significant digits
// for a double: 1e+22, 100; integers and text whole).
template <class T>
[[noreturn]] void bad_field(const std::string& field, const T& value, const std::string& accepted) {
  std::ostringstream os;
  os << value;
  throw InvalidField(field, os.str(), accepted);
}

}  // namespace knitsim
