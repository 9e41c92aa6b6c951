#pragma once
/// \file
/// Tests of bad input: the message of the InputError a call throws.

#include <functional>
#include <string>

#include "ifab/core/error.h"

namespace ifab::testing {

/// The what() of the InputError `f` throws, or "" if it throws none.
inline std::string ErrorOf(const std::function<void()>& f) {
  try {
    f();
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace ifab::testing
