#include <gtest/gtest.h>

#include "ssta/core/classes.h"

namespace ssta {
namespace {

TEST(Classes, ColoursFollowTheInterfaceTable) {
  EXPECT_EQ(ClassColour(TravClass::kTraversable), (Rgb8{0, 255, 0}));
  EXPECT_EQ(ClassColour(TravClass::kSemiTraversable), (Rgb8{0, 0, 255}));
  EXPECT_EQ(ClassColour(TravClass::kNonTraversable), (Rgb8{255, 0, 0}));
  EXPECT_EQ(ClassColour(TravClass::kUnknown), (Rgb8{0, 0, 0}));
}

TEST(Classes, WorseOrdersTraversableBelowNonTraversable) {
  EXPECT_EQ(Worse(TravClass::kTraversable, TravClass::kSemiTraversable), TravClass::kSemiTraversable);
  EXPECT_EQ(Worse(TravClass::kNonTraversable, TravClass::kTraversable), TravClass::kNonTraversable);
  EXPECT_THROW(Worse(TravClass::kUndecided, TravClass::kTraversable), InternalError);
}

TEST(Classes, OverlayTintsByClassAndLeavesUndecidedAlone) {
  ImageU8 grey(4, 1, 100);
  ImageU8 labels(4, 1);
  labels[0] = 0;
  labels[1] = 1;
  labels[2] = 3;
  labels[3] = 4;
  const ImageRgb out = MakeOverlay(grey, labels, 0.5f);
  EXPECT_LT(out[0].r, 100);                 // unknown darkened
  EXPECT_GT(out[1].g, out[1].r + 50);       // traversable green
  EXPECT_GT(out[2].r, out[2].g + 50);       // non-traversable red
  EXPECT_EQ(out[3], (Rgb8{100, 100, 100}));  // undecided shows the image
}

}  // namespace
}  // namespace ssta
