#include "ifab/base/planner/planning_scene.h"

#include <gtest/gtest.h>

#include "brick_stacking_scene.h"

namespace ifab::base {
namespace {
TEST(PlanningScene, Placeholder) { SUCCEED(); }
}  // namespace
}  // namespace ifab::base
