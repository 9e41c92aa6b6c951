#pragma once
// Shared by the libFuzzer harnesses (issue 14). A harness feeds the bytes to one parser; bad
// input must end in an ifab::InputError (the CLI's exit code 2). Anything else that escapes
// (another exception type, a crash, a sanitizer report, a hang, an allocation over
// -rss_limit_mb) is a finding.
#include <cstddef>
#include <cstdint>
#include <string>

#include "ifab/core/error.h"

#define IFAB_FUZZ_TARGET(body)                                                      \
  extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) { \
    const std::string input(reinterpret_cast<const char*>(data), size);             \
    try {                                                                           \
      body                                                                          \
    } catch (const ::ifab::InputError&) {                                           \
    }                                                                               \
    return 0;                                                                       \
  }
