// SSTA's PNG and JPEG codecs (libpng, libjpeg) against OpenCV's imdecode and imencode, which
// they replace: the same pixels for every layout a camera, a bag or a truth file brings.

#include "ssta/io/image_codec.h"

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <opencv2/imgcodecs.hpp>
#include <png.h>
#include <zlib.h>

#include "ssta/core/error.h"

namespace ssta {
namespace {

/// A textured image of `type` (8 or 16-bit, 1, 2, 3 or 4 channels) with random pixels over a
/// ramp, so that both smooth and noisy areas are coded.
cv::Mat Textured(int type, int seed) {
  cv::Mat m(37, 53, type);
  std::mt19937 random(seed);
  const int max = CV_MAT_DEPTH(type) == CV_16U ? 65535 : 255;
  std::uniform_int_distribution<int> noise(0, max / 8);
  for (int v = 0; v < m.rows; ++v) {
    for (int u = 0; u < m.cols * m.channels(); ++u) {
      const int value = std::min(max, (u + 3 * v) * max / (m.cols * m.channels() + 3 * m.rows) + noise(random));
      if (CV_MAT_DEPTH(type) == CV_16U) {
        m.ptr<std::uint16_t>(v)[u] = static_cast<std::uint16_t>(value);
      } else {
        m.ptr<std::uint8_t>(v)[u] = static_cast<std::uint8_t>(value);
      }
    }
  }
  return m;
}

std::vector<unsigned char> Encoded(const cv::Mat& m, const std::string& ext, const std::vector<int>& params = {}) {
  std::vector<unsigned char> bytes;
  EXPECT_TRUE(cv::imencode(ext, m, bytes, params));
  return bytes;
}

/// The number of pixels where `image` and OpenCV's 8-bit grey decoding of `bytes` differ.
int GreyDifferences(const ImageU8& image, const std::vector<unsigned char>& bytes) {
  const cv::Mat reference = cv::imdecode(bytes, cv::IMREAD_GRAYSCALE);
  EXPECT_EQ(image.width(), reference.cols);
  EXPECT_EQ(image.height(), reference.rows);
  if (image.width() != reference.cols || image.height() != reference.rows) return -1;
  int differ = 0;
  for (int v = 0; v < reference.rows; ++v) {
    for (int u = 0; u < reference.cols; ++u) differ += image(v, u) != reference.at<std::uint8_t>(v, u);
  }
  return differ;
}

TEST(ImageCodec, GreyDecodingMatchesOpenCvForEveryLayout) {
  struct Case {
    const char* name;
    cv::Mat image;
    const char* ext;
  };
  const std::vector<Case> cases = {
      {"grey PNG", Textured(CV_8UC1, 1), ".png"},
      {"16-bit grey PNG (the high byte)", Textured(CV_16UC1, 2), ".png"},
      {"colour PNG", Textured(CV_8UC3, 3), ".png"},
      {"colour PNG with alpha", Textured(CV_8UC4, 4), ".png"},
      {"16-bit colour PNG", Textured(CV_16UC3, 5), ".png"},
      {"grey JPEG", Textured(CV_8UC1, 6), ".jpg"},
      {"colour JPEG", Textured(CV_8UC3, 7), ".jpg"},
  };
  for (const Case& c : cases) {
    const std::vector<unsigned char> bytes = Encoded(c.image, c.ext);
    EXPECT_EQ(GreyDifferences(DecodeGrey(bytes.data(), bytes.size(), c.name), bytes), 0) << c.name;
  }
}

/// A PNG written by libpng's simplified API from 8-bit `pixels` in `format` (with `colormap`
/// for the colour-mapped formats).
std::vector<unsigned char> LibpngEncoded(const std::vector<unsigned char>& pixels, int width, int height,
                                         png_uint_32 format, const std::vector<unsigned char>& colormap = {}) {
  png_image image{};
  image.version = PNG_IMAGE_VERSION;
  image.width = static_cast<png_uint_32>(width);
  image.height = static_cast<png_uint_32>(height);
  image.format = format;
  image.colormap_entries = static_cast<png_uint_32>(colormap.size() / 4);
  png_alloc_size_t size = 0;
  const void* map = colormap.empty() ? nullptr : colormap.data();
  EXPECT_TRUE(png_image_write_to_memory(&image, nullptr, &size, 0, pixels.data(), 0, map)) << image.message;
  std::vector<unsigned char> bytes(size);
  EXPECT_TRUE(png_image_write_to_memory(&image, bytes.data(), &size, 0, pixels.data(), 0, map)) << image.message;
  bytes.resize(size);
  return bytes;
}

TEST(ImageCodec, PalettesWithTransparencyAndGreyWithAlphaDecodeAsOpenCv) {
  // Four colours, two of them partly transparent: libpng writes a palette and a tRNS chunk.
  const std::vector<unsigned char> colormap = {255, 0, 0, 255, 0, 200, 0, 128, 20, 40, 250, 0, 90, 90, 90, 255};
  std::vector<unsigned char> indices(31 * 17);
  for (std::size_t i = 0; i < indices.size(); ++i) indices[i] = static_cast<unsigned char>((i * 7 + i / 31) % 4);
  std::vector<unsigned char> bytes = LibpngEncoded(indices, 31, 17, PNG_FORMAT_RGBA_COLORMAP, colormap);
  EXPECT_EQ(GreyDifferences(DecodeGrey(bytes.data(), bytes.size(), "palette.png"), bytes), 0);
  // Grey and alpha.
  std::vector<unsigned char> grey_alpha(31 * 17 * 2);
  for (std::size_t i = 0; i < grey_alpha.size(); ++i) grey_alpha[i] = static_cast<unsigned char>(i * 37);
  bytes = LibpngEncoded(grey_alpha, 31, 17, PNG_FORMAT_GA);
  EXPECT_EQ(GreyDifferences(DecodeGrey(bytes.data(), bytes.size(), "ga.png"), bytes), 0);
  const StoredPng stored = DecodePngAsStored(bytes.data(), bytes.size(), "ga.png");
  EXPECT_EQ(stored.channels, 2);
  EXPECT_TRUE(stored.u8.empty());
}

TEST(ImageCodec, BinaryPgmsDecodeAsOpenCvReadsThem) {
  const cv::Mat grid = Textured(CV_8UC1, 13);
  std::vector<unsigned char> bytes = Encoded(grid, ".pgm");
  EXPECT_EQ(GreyDifferences(DecodeGrey(bytes.data(), bytes.size(), "grid.pgm"), bytes), 0);
  // A comment in the header, as map_server's tools write one.
  const std::string commented = "P5\n# grid\n3 2\n255\n\x01\x02\x03\x04\x05\x06";
  const ImageU8 small = DecodeGrey(commented.data(), commented.size(), "c.pgm");
  ASSERT_EQ(small.width(), 3);
  ASSERT_EQ(small.height(), 2);
  EXPECT_EQ(small(1, 2), 6);
}

TEST(ImageCodec, OneChannelPngsDecodeAsStoredAndOthersSayWhatTheyHold) {
  const cv::Mat depth = Textured(CV_16UC1, 8);
  std::vector<unsigned char> bytes = Encoded(depth, ".png");
  StoredPng png = DecodePngAsStored(bytes.data(), bytes.size(), "depth.png");
  ASSERT_EQ(png.channels, 1);
  ASSERT_EQ(png.bit_depth, 16);
  ASSERT_EQ(png.u16.width(), depth.cols);
  int differ = 0;
  for (int v = 0; v < depth.rows; ++v) {
    for (int u = 0; u < depth.cols; ++u) differ += png.u16(v, u) != depth.at<std::uint16_t>(v, u);
  }
  EXPECT_EQ(differ, 0);

  const cv::Mat labels = Textured(CV_8UC1, 9);
  bytes = Encoded(labels, ".png");
  png = DecodePngAsStored(bytes.data(), bytes.size(), "labels.png");
  ASSERT_EQ(png.bit_depth, 8);
  ASSERT_EQ(png.u8.height(), labels.rows);
  EXPECT_EQ(png.u8(11, 17), labels.at<std::uint8_t>(11, 17));
  EXPECT_EQ(png.u8(labels.rows - 1, labels.cols - 1), labels.at<std::uint8_t>(labels.rows - 1, labels.cols - 1));

  bytes = Encoded(Textured(CV_8UC3, 10), ".png");
  png = DecodePngAsStored(bytes.data(), bytes.size(), "colour.png");
  EXPECT_EQ(png.channels, 3);
  EXPECT_TRUE(png.u8.empty() && png.u16.empty());
}

TEST(ImageCodec, EncodedPngsReadBackInOpenCvAtAnyLevel) {
  ImageU16 depth(41, 23);
  ImageRgb colour(41, 23);
  for (int v = 0; v < depth.height(); ++v) {
    for (int u = 0; u < depth.width(); ++u) {
      depth(v, u) = static_cast<std::uint16_t>(1000 * v + 37 * u);
      colour(v, u) = Rgb8{static_cast<std::uint8_t>(5 * u), static_cast<std::uint8_t>(9 * v), 200};
    }
  }
  for (const int level : {1, 6, 9}) {
    const std::vector<unsigned char> depth_png = EncodePng(depth, level, "depth.png");
    const cv::Mat d = cv::imdecode(depth_png, cv::IMREAD_UNCHANGED);
    ASSERT_EQ(d.type(), CV_16UC1) << level;
    EXPECT_EQ(d.at<std::uint16_t>(22, 40), depth(22, 40)) << level;
    EXPECT_EQ(d.at<std::uint16_t>(7, 3), depth(7, 3)) << level;
    const cv::Mat c = cv::imdecode(EncodePng(colour, level, "colour.png"), cv::IMREAD_COLOR);
    ASSERT_EQ(c.type(), CV_8UC3) << level;
    const cv::Vec3b bgr = c.at<cv::Vec3b>(20, 30);
    EXPECT_EQ(bgr[2], colour(20, 30).r);
    EXPECT_EQ(bgr[1], colour(20, 30).g);
    EXPECT_EQ(bgr[0], colour(20, 30).b);
  }
  // Level 9 compresses a smooth picture more than level 1.
  EXPECT_LT(EncodePng(colour, 9, "c.png").size(), EncodePng(colour, 1, "c.png").size());
}

TEST(ImageCodec, DamagedDataIsAnErrorNamingWhere) {
  const auto message = [](const std::vector<unsigned char>& bytes) {
    try {
      DecodeGrey(bytes.data(), bytes.size(), "cam0/1.png");
    } catch (const Error& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string text = "not an image";
  EXPECT_EQ(message({text.begin(), text.end()}),
            "cam0/1.png: not a PNG, JPEG or PGM image (the formats read: PNG, JPEG, 8-bit binary PGM)");
  const std::string short_pgm = "P5 4 2 255\n1234567";
  EXPECT_EQ(message({short_pgm.begin(), short_pgm.end()}),
            "cam0/1.png: cannot decode PGM: the data ends early (truncated)");
  // A width of eight digits is not read as a seven-digit width and a height.
  const std::string long_pgm = "P5 12345678 1 255\n" + std::string(64, 'x');
  EXPECT_EQ(message({long_pgm.begin(), long_pgm.end()}),
            "cam0/1.png: cannot decode PGM: a bad header (8-bit binary P5 is read)");
  std::vector<unsigned char> png = Encoded(Textured(CV_8UC1, 11), ".png");
  png.resize(png.size() / 2);
  EXPECT_EQ(message(png).rfind("cam0/1.png: cannot decode PNG: ", 0), 0u) << message(png);
  std::vector<unsigned char> jpeg = Encoded(Textured(CV_8UC3, 12), ".jpg");
  jpeg.resize(200);  // the headers, not the scan
  EXPECT_EQ(message(jpeg).rfind("cam0/1.png: cannot decode JPEG: ", 0), 0u) << message(jpeg);
  EXPECT_THROW(DecodePngAsStored(jpeg.data(), jpeg.size(), "x"), Error);
  // Cut inside the scan: libjpeg alone would fill the rest with grey.
  std::vector<unsigned char> cut_scan = Encoded(Textured(CV_8UC1, 13), ".jpg");
  ASSERT_GT(cut_scan.size(), 1200u);
  cut_scan.resize(cut_scan.size() - 400);
  EXPECT_EQ(message(cut_scan), "cam0/1.png: cannot decode JPEG: the data ends early (truncated)");
  // Cut inside the scan and closed with an end-of-image marker: libjpeg meets the marker
  // before the scan's data is complete and would fill the rest with grey.
  cut_scan.push_back(0xff);
  cut_scan.push_back(0xd9);
  EXPECT_EQ(message(cut_scan), "cam0/1.png: cannot decode JPEG: the scan ends early at a marker (damaged or truncated)");

  // A header that claims 50000 x 50000 px (valid CRCs, an empty IDAT) is refused before
  // anything is allocated for its pixels.
  std::vector<unsigned char> huge = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  const auto chunk = [&huge](const std::string& type, const std::vector<unsigned char>& data) {
    for (const int shift : {24, 16, 8, 0}) huge.push_back(static_cast<unsigned char>(data.size() >> shift));
    const std::size_t start = huge.size();
    huge.insert(huge.end(), type.begin(), type.end());
    huge.insert(huge.end(), data.begin(), data.end());
    const auto crc = static_cast<std::uint32_t>(crc32(0L, huge.data() + start, static_cast<uInt>(huge.size() - start)));
    for (const int shift : {24, 16, 8, 0}) huge.push_back(static_cast<unsigned char>(crc >> shift));
  };
  chunk("IHDR", {0, 0, 0xc3, 0x50, 0, 0, 0xc3, 0x50, 8, 0, 0, 0, 0});
  chunk("IDAT", {});
  chunk("IEND", {});
  EXPECT_EQ(message(huge), "cam0/1.png: cannot decode PNG: the image is larger than 2^30 pixels");
  // 20000 x 20000 px is allowed, but not from a file of 57 bytes: deflate cannot expand that far.
  huge.resize(8);
  chunk("IHDR", {0, 0, 0x4e, 0x20, 0, 0, 0x4e, 0x20, 8, 0, 0, 0, 0});
  chunk("IDAT", {});
  chunk("IEND", {});
  EXPECT_EQ(message(huge),
            "cam0/1.png: cannot decode PNG: the data is far too short for the size its header claims (damaged or truncated)");
}

}  // namespace
}  // namespace ssta
