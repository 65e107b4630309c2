#include "ssta/io/image_io.h"

#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ssta/core/error.h"
#include "ssta/io/file_util.h"

namespace ssta {
namespace {

cv::Mat ReadMat(const std::string& path, int flags) {
  if (!std::filesystem::exists(path)) throw Error(path + ": image file not found");
  cv::Mat m;
  try {
    m = cv::imread(path, flags);
  } catch (const cv::Exception& e) {
    throw Error(path + ": cannot decode image: " + e.what());
  }
  if (m.empty()) throw Error(path + ": cannot decode image (corrupt or truncated?)");
  return m;
}

template <typename T>
Image<T> FromMat(const cv::Mat& m) {
  Image<T> out(m.cols, m.rows);
  for (int v = 0; v < m.rows; ++v) {
    const T* src = m.ptr<T>(v);
    std::copy(src, src + m.cols, out.row(v));
  }
  return out;
}

void WriteMat(const cv::Mat& m, const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  WriteFileAtomically(path, [&](const std::string& tmp) {
    std::vector<uchar> buffer;
    bool ok = false;
    try {
      ok = cv::imencode(ext, m, buffer);
    } catch (const cv::Exception& e) {
      throw Error(path + ": cannot encode image: " + e.what());
    }
    if (!ok) throw Error(path + ": cannot encode image as " + ext);
    FILE* f = std::fopen(tmp.c_str(), "wb");
    if (!f) throw Error(path + ": cannot open for writing");
    const size_t n = std::fwrite(buffer.data(), 1, buffer.size(), f);
    const int rc = std::fclose(f);
    if (n != buffer.size() || rc != 0) throw Error(path + ": write failed (disk full?)");
  });
}

}  // namespace

ImageU8 ReadGreyImage(const std::string& path) {
  return FromMat<std::uint8_t>(ReadMat(path, cv::IMREAD_GRAYSCALE));
}

ImageU8 ReadLabelImage(const std::string& path) {
  const cv::Mat m = ReadMat(path, cv::IMREAD_UNCHANGED);
  if (m.type() != CV_8UC1) throw Error(path + ": expected an 8-bit single-channel label image");
  return FromMat<std::uint8_t>(m);
}

ImageU16 ReadImageU16(const std::string& path) {
  const cv::Mat m = ReadMat(path, cv::IMREAD_UNCHANGED);
  if (m.type() != CV_16UC1) throw Error(path + ": expected a 16-bit single-channel image");
  return FromMat<std::uint16_t>(m);
}

void WriteImage(const ImageU8& image, const std::string& path) {
  WriteMat(cv::Mat(image.height(), image.width(), CV_8UC1, const_cast<std::uint8_t*>(image.data())), path);
}

void WriteImage(const ImageU16& image, const std::string& path) {
  WriteMat(cv::Mat(image.height(), image.width(), CV_16UC1, const_cast<std::uint16_t*>(image.data())), path);
}

void WriteImage(const ImageRgb& image, const std::string& path) {
  cv::Mat rgb(image.height(), image.width(), CV_8UC3, const_cast<Rgb8*>(image.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  WriteMat(bgr, path);
}

}  // namespace ssta
