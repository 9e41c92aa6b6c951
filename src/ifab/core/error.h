#pragma once
/// \file
/// Three kinds of error (STYLE.md): a bug aborts with IFAB_CHECK; bad input from a user or caller
/// throws ifab::InputError with a message naming the file/field and what was expected; a numerical
/// outcome is returned as a status, never thrown.

#include <fmt/format.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>
#include <string>

namespace ifab {

/// Bad input: a malformed file, field or argument. The CLI turns it into exit code 2.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Throw an InputError with a fmt-formatted message.
template <typename... Args>
[[noreturn]] void ThrowInputError(fmt::format_string<Args...> format, Args&&... args) {
  throw InputError(fmt::format(format, std::forward<Args>(args)...));
}

namespace internal {
[[noreturn]] inline void CheckFailed(const char* condition, const char* file, int line) {
  std::fprintf(stderr, "ifab: internal check failed: %s at %s:%d\n", condition, file, line);
  std::abort();
}
}  // namespace internal

}  // namespace ifab

/// A programming error (an invariant of our own code): abort with the location.
#define IFAB_CHECK(condition)                                            \
  do {                                                                   \
    if (!(condition)) ::ifab::internal::CheckFailed(#condition, __FILE__, __LINE__); \
  } while (false)

/// A caller's argument that must hold: throws InputError naming the condition.
#define IFAB_THROW_UNLESS(condition, ...)                                        \
  do {                                                                           \
    if (!(condition)) ::ifab::ThrowInputError(__VA_ARGS__);                      \
  } while (false)
