#pragma once
/// \file
/// Numbers given on the command line ("1.5 0 90", "1.5,0,90").

#include <cstddef>
#include <string>
#include <vector>

namespace ifab {

/// Exactly `n` finite numbers separated by spaces and/or commas. Throws InputError naming `what`
/// (e.g. "--goal") and the offending token otherwise.
std::vector<double> ParseNumbers(const std::string& text, const std::string& what, std::size_t n);

}  // namespace ifab
