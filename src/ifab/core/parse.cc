#include "ifab/core/parse.h"

#include <cmath>
#include <sstream>

#include "ifab/core/error.h"

namespace ifab {

std::vector<double> ParseNumbers(const std::string& text, const std::string& what, std::size_t n) {
  std::string s = text;
  for (char& ch : s)
    if (ch == ',') ch = ' ';
  std::istringstream in(s);
  std::vector<double> v;
  std::string token;
  while (in >> token) {
    std::size_t used = 0;
    double x = 0.0;
    try {
      x = std::stod(token, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != token.size() || !std::isfinite(x))
      ThrowInputError("{}: expected {} numbers, got '{}' ('{}' is not a number)", what, n, text, token);
    v.push_back(x);
  }
  if (v.size() != n) ThrowInputError("{}: expected {} numbers, got {} in '{}'", what, n, v.size(), text);
  return v;
}

}  // namespace ifab
