#include "ifab/base/planner/site_scene.h"

#include <gtest/gtest.h>

#include "brick_stacking_scene.h"
#include "ifab/core/data_path.h"

namespace ifab::base {
namespace {
TEST(SiteScene, Placeholder) { SUCCEED(); }
}  // namespace
}  // namespace ifab::base
