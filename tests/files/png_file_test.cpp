// The libpng writer checked against an independent decoder (OpenCV's imread).
#include "ssta/files/png_file.h"

#include <filesystem>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>

#include "ssta/core/error.h"
#include "temp_dir.h"

namespace ssta {
namespace {

TEST(PngFile, GreyPixelsDecodeToTheValuesWritten) {
  testing::TempDir dir;
  ImageU8 image(37, 5);  // odd width: rows are not padded
  for (int v = 0; v < image.height(); ++v) {
    for (int u = 0; u < image.width(); ++u) image(v, u) = static_cast<std::uint8_t>((v * 53 + u * 7) % 256);
  }
  WritePng(image, dir / "grey.png");
  const cv::Mat m = cv::imread(dir / "grey.png", cv::IMREAD_UNCHANGED);
  ASSERT_EQ(m.type(), CV_8UC1);
  ASSERT_EQ(m.cols, 37);
  ASSERT_EQ(m.rows, 5);
  for (int v = 0; v < m.rows; ++v) {
    for (int u = 0; u < m.cols; ++u) EXPECT_EQ(m.at<std::uint8_t>(v, u), image(v, u)) << "(" << v << ", " << u << ")";
  }
}

TEST(PngFile, ColourPixelsDecodeToTheValuesWrittenInRgbOrder) {
  testing::TempDir dir;
  ImageRgb image(3, 2);
  image(0, 0) = Rgb8{255, 0, 0};
  image(0, 1) = Rgb8{0, 255, 0};
  image(0, 2) = Rgb8{0, 0, 255};
  image(1, 0) = Rgb8{10, 20, 30};
  image(1, 2) = Rgb8{200, 100, 50};
  WritePng(image, dir / "colour.png");
  const cv::Mat m = cv::imread(dir / "colour.png", cv::IMREAD_UNCHANGED);  // B, G, R
  ASSERT_EQ(m.type(), CV_8UC3);
  for (int v = 0; v < 2; ++v) {
    for (int u = 0; u < 3; ++u) {
      const cv::Vec3b bgr = m.at<cv::Vec3b>(v, u);
      EXPECT_EQ(bgr[2], image(v, u).r);
      EXPECT_EQ(bgr[1], image(v, u).g);
      EXPECT_EQ(bgr[0], image(v, u).b);
    }
  }
}

TEST(PngFile, AnEmptyImageOrAMissingFolderIsAnErrorNamingTheFile) {
  testing::TempDir dir;
  try {
    WritePng(ImageU8(), dir / "empty.png");
    FAIL() << "an empty image was written";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("empty.png"), std::string::npos) << e.what();
  }
  EXPECT_THROW(WritePng(ImageRgb(2, 2), dir / "no/such/folder/x.png"), Error);
  EXPECT_FALSE(std::filesystem::exists(dir / "empty.png"));
}

}  // namespace
}  // namespace ssta
