#pragma once

#include <functional>

namespace ssta {

/// Called after each unit of a long run (a frame, a file): (units done, units to do). Every
/// long-running function takes one; an empty one is not called.
using Progress = std::function<void(int done, int total)>;

}  // namespace ssta
