#include "ssta/io/image_io.h"

#include <array>
#include <cstdint>
#include <filesystem>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"

namespace ssta {
namespace {

std::uint32_t Crc32(const unsigned char* data, std::size_t n, std::uint32_t crc = 0xffffffffu) {
  static const auto table = [] {
    std::array<std::uint32_t, 256> t{};
    for (std::uint32_t i = 0; i < 256; ++i) {
      std::uint32_t c = i;
      for (int k = 0; k < 8; ++k) c = (c & 1u) ? 0xedb88320u ^ (c >> 1) : c >> 1;
      t[i] = c;
    }
    return t;
  }();
  for (std::size_t i = 0; i < n; ++i) crc = table[(crc ^ data[i]) & 0xffu] ^ (crc >> 8);
  return crc;
}

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

/// Walks a PNG's chunks and checks each one's CRC, so that a truncated or damaged file is
/// reported here in one line: handed to OpenCV, libpng would print its own complaint to
/// stderr first.
void CheckPng(const std::string& bytes, const std::string& path) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  std::size_t pos = 8;  // after the signature
  while (pos + 12 <= bytes.size()) {
    const std::uint32_t length = BigEndian32(p + pos);
    const std::string type(bytes, pos + 4, 4);
    if (length > bytes.size() - pos - 12) break;  // the chunk runs past the end
    const std::uint32_t crc = Crc32(p + pos + 4, length + 4) ^ 0xffffffffu;  // over type and data
    if (crc != BigEndian32(p + pos + 8 + length)) {
      throw Error(path + ": corrupt PNG (CRC error in its " + type + " chunk)");
    }
    if (type == "IEND") return;
    pos += 12 + length;
  }
  throw Error(path + ": truncated PNG (the file ends before its IEND chunk)");
}

cv::Mat ReadMat(const std::string& path, int flags) {
  if (!std::filesystem::exists(path)) throw Error(path + ": image file not found");
  const std::string bytes = ReadTextFile(path);
  static const std::string kPngSignature("\x89PNG\r\n\x1a\n", 8);
  if (bytes.compare(0, kPngSignature.size(), kPngSignature) == 0) CheckPng(bytes, path);
  // JPEG: a file cut short lacks the end-of-image marker near its end (some writers pad after
  // it); libjpeg would only warn on stderr and decode the rest as grey.
  if (bytes.compare(0, 2, "\xff\xd8") == 0) {
    const std::size_t tail = bytes.size() > 1024 ? bytes.size() - 1024 : 2;
    if (bytes.find("\xff\xd9", tail) == std::string::npos) throw Error(path + ": truncated JPEG (no end-of-image marker)");
  }
  cv::Mat m;
  try {
    const cv::Mat buffer(1, static_cast<int>(bytes.size()), CV_8UC1, const_cast<char*>(bytes.data()));
    m = cv::imdecode(buffer, flags);
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

void WriteMat(const cv::Mat& m, const std::string& path, const std::vector<int>& params = {}) {
  const std::string ext = std::filesystem::path(path).extension().string();
  WriteFileAtomically(path, [&](const std::string& tmp) {
    std::vector<uchar> buffer;
    bool ok = false;
    try {
      ok = cv::imencode(ext, m, buffer, params);
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

/// An RGB image written as OpenCV wants it (BGR), with imencode's `params`.
void WriteRgb(const ImageRgb& image, const std::string& path, const std::vector<int>& params) {
  cv::Mat rgb(image.height(), image.width(), CV_8UC3, const_cast<Rgb8*>(image.data()));
  cv::Mat bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  WriteMat(bgr, path, params);
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

void WriteImage(const ImageRgb& image, const std::string& path) { WriteRgb(image, path, {}); }

void WriteImageCompact(const ImageRgb& image, const std::string& path) {
  WriteRgb(image, path, {cv::IMWRITE_PNG_COMPRESSION, 9});
}

}  // namespace ssta
