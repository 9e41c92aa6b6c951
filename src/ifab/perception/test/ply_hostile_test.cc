// Issue 14: hostile PLY files. Each case here was accepted, misread or crashed before.
#include <gtest/gtest.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstring>
#include <fstream>
#include <sstream>

#include "ifab/core/testing/error_of.h"
#include "ifab/perception/ply.h"

namespace ifab {
namespace {

using testing::ErrorOf;

std::string ErrorOfText(const std::string& text) {
  return ErrorOf([&] {
    std::istringstream in(text);
    ReadPly(in, "hostile.ply");
  });
}

std::string Binary(const std::string& header, const std::vector<float>& values) {
  std::string s = header;
  for (float v : values) s.append(reinterpret_cast<const char*>(&v), 4);
  return s;
}

const char* kXyzFloatLe =
    "ply\nformat binary_little_endian 1.0\nelement vertex 1\nproperty float x\nproperty float y\n"
    "property float z\nend_header\n";

TEST(PlyHostile, RejectsNonFiniteCoordinatesInAsciiAndBinary) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  EXPECT_NE(ErrorOfText(head + "1 nan 3\n").find("vertex 0, property y: expected a finite number"), std::string::npos);
  EXPECT_NE(ErrorOfText(head + "inf 2 3\n").find("property x: expected a finite number"), std::string::npos);
  EXPECT_NE(ErrorOfText(head + "1 2 1e999\n").find("property z: expected a finite number"), std::string::npos);
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(ErrorOf([&] {
              std::istringstream in(Binary(kXyzFloatLe, {1.0f, 2.0f, nan}));
              ReadPly(in, "hostile.ply");
            }).find("hostile.ply: vertex 0, property z: expected a finite number"),
            std::string::npos);
  const float inf = std::numeric_limits<float>::infinity();
  EXPECT_NE(ErrorOf([&] {
              std::istringstream in(Binary(kXyzFloatLe, {-inf, 2.0f, 3.0f}));
              ReadPly(in, "hostile.ply");
            }).find("expected a finite number"),
            std::string::npos);
}

TEST(PlyHostile, RejectsAnElementCountThatOverflows) {
  const std::string e = ErrorOfText("ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\nend_header\n");
  EXPECT_NE(e.find("hostile.ply: line 3: expected 'element <name> <count>' with a count >= 0"), std::string::npos) << e;
}

TEST(PlyHostile, RejectsPropertylessElementsWithAHugeCount) {
  // Before: 9.2e18 empty iterations (the test would time out).
  const std::string e = ErrorOfText(
      "ply\nformat binary_little_endian 1.0\nelement junk 9223372036854775807\nelement vertex 0\n"
      "property float x\nproperty float y\nproperty float z\nend_header\n");
  EXPECT_NE(e.find("element 'junk' declares 9223372036854775807 instances but no properties"), std::string::npos) << e;
}

TEST(PlyHostile, RejectsListCountsThatAreNotWholeNumbersOfTheirType) {
  const std::string head =
      "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
      "property list float float extra\nend_header\n";
  EXPECT_NE(ErrorOfText(head + "1 2 3 -1 0\n").find("list 'extra' has length -1, expected a whole number"),
            std::string::npos);
  EXPECT_NE(ErrorOfText(head + "1 2 3 nan 0\n").find("list 'extra' has length nan"), std::string::npos);
  EXPECT_NE(ErrorOfText(head + "1 2 3 2.5 0 0 0\n").find("has length 2.5"), std::string::npos);
  // In a skipped element too (a binary float count of -1e30 before).
  std::string face = "ply\nformat binary_little_endian 1.0\nelement face 1\nproperty list float int idx\n"
                     "element vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n";
  face = Binary(face, {-1e30f});
  const std::string e = ErrorOf([&] {
    std::istringstream in(face);
    ReadPly(in, "hostile.ply");
  });
  EXPECT_NE(e.find("list 'idx' has length -1"), std::string::npos) << e;
}

// A 150-byte file claiming 199,999,999 vertices with 40 fields: the reader must fail on the
// missing data without first allocating what the header claims (~70 GB). Run in a child
// process whose address space is capped at 1 GB above what it uses now. AddressSanitizer
// reserves terabytes of shadow memory, so the cap cannot be applied under it.
#if defined(__SANITIZE_ADDRESS__)
#define IFAB_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define IFAB_ASAN 1
#endif
#endif
TEST(PlyHostile, DoesNotReserveWhatTheHeaderClaimsBeforeReadingData) {
#ifdef IFAB_ASAN
  GTEST_SKIP() << "address-space cap not possible under AddressSanitizer";
#else
  std::string header = "ply\nformat binary_little_endian 1.0\nelement vertex 199999999\nproperty double x\n"
                       "property double y\nproperty double z\n";
  for (int i = 0; i < 40; ++i) header += "property double f" + std::to_string(i) + "\n";
  header += "end_header\n";
  const std::string text = header + std::string(100, '\0');
  const pid_t pid = fork();
  ASSERT_GE(pid, 0);
  if (pid == 0) {
    long pages = 0;
    std::ifstream("/proc/self/statm") >> pages;
    const rlim_t cap = static_cast<rlim_t>(pages) * static_cast<rlim_t>(sysconf(_SC_PAGESIZE)) + (1ull << 30);
    const rlimit limit{cap, cap};
    setrlimit(RLIMIT_AS, &limit);
    int code = 3;
    try {
      std::istringstream in(text);
      ReadPly(in, "hostile.ply");
      code = 4;
    } catch (const InputError& e) {
      code = std::strstr(e.what(), "the data ends at vertex 0") ? 0 : 5;
    } catch (const std::bad_alloc&) {
      code = 6;
    }
    _exit(code);
  }
  int status = 0;
  ASSERT_EQ(waitpid(pid, &status, 0), pid);
  ASSERT_TRUE(WIFEXITED(status));
  EXPECT_EQ(WEXITSTATUS(status), 0) << "6 = bad_alloc: the reader reserved what the header claimed";
#endif
}

}  // namespace
}  // namespace ifab
