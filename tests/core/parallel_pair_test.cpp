#include "core/parallel_pair.h"

#include <atomic>
#include <stdexcept>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

namespace ssta::internal {
namespace {

TEST(RunPair, RunsBothPartsAndRethrowsTheFirstErrorAfterBoth) {
  SetPairRunner(nullptr);  // the default: a thread of its own for part 1
  int ran[2] = {0, 0};
  std::thread::id ids[2];
  RunPair([&](int part) {
    ++ran[part];
    ids[part] = std::this_thread::get_id();
  });
  EXPECT_EQ(ran[0], 1);
  EXPECT_EQ(ran[1], 1);
  EXPECT_EQ(ids[0], std::this_thread::get_id());
  EXPECT_NE(ids[1], std::this_thread::get_id());

  std::atomic<int> finished{0};
  EXPECT_THROW(RunPair([&](int part) {
                 if (part == 1) throw std::runtime_error("part 1");
                 ++finished;
               }),
               std::runtime_error);
  EXPECT_EQ(finished.load(), 1) << "part 0 runs to its end although part 1 threw";
}

TEST(RunPair, ASerialThreadRunsThePartsInOrderOnItself) {
  SerialOnThisThread() = true;
  std::vector<int> order;
  std::thread::id ids[2];
  RunPair([&](int part) {
    order.push_back(part);
    ids[part] = std::this_thread::get_id();
  });
  SerialOnThisThread() = false;
  EXPECT_EQ(order, (std::vector<int>{0, 1}));
  EXPECT_EQ(ids[1], std::this_thread::get_id());
}

TEST(RunPair, AnInstalledRunnerRunsTheParts) {
  static int calls = 0;
  calls = 0;
  SetPairRunner([](const std::function<void(int)>& part) {
    ++calls;
    part(1);
    part(0);
  });
  int sum = 0;
  RunPair([&](int part) { sum += part + 1; });
  SetPairRunner(nullptr);
  EXPECT_EQ(calls, 1);
  EXPECT_EQ(sum, 3);
}

}  // namespace
}  // namespace ssta::internal
