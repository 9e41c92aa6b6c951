// Number lists given on the command line ("--goal '1.5 0 90'", "--from 0,-30,30,0,90,0").
#include "fuzz_common.h"
#include "ifab/core/parse.h"

IFAB_FUZZ_TARGET({
  // The first byte picks how many numbers are expected (the CLI asks for 3 or 6).
  const std::size_t n = input.empty() ? 3 : static_cast<std::uint8_t>(input[0]) % 8;
  const auto v = ifab::ParseNumbers(input.empty() ? input : input.substr(1), "--fuzz", n);
  if (v.size() != n) __builtin_trap();
})
