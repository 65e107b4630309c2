#include "ssta/io/image_io.h"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

#include <zlib.h>

#include "ssta/core/error.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_codec.h"

namespace ssta {
namespace {

std::uint32_t BigEndian32(const unsigned char* p) {
  return (std::uint32_t{p[0]} << 24) | (std::uint32_t{p[1]} << 16) | (std::uint32_t{p[2]} << 8) | p[3];
}

/// Walks a PNG's chunks and checks each one's CRC, so that a truncated or damaged file is
/// reported in one line naming the damaged chunk before any decoding.
void CheckPng(const std::string& bytes, const std::string& path) {
  const auto* p = reinterpret_cast<const unsigned char*>(bytes.data());
  std::size_t pos = 8;  // after the signature
  while (pos + 12 <= bytes.size()) {
    const std::uint32_t length = BigEndian32(p + pos);
    const std::string type(bytes, pos + 4, 4);
    if (length > bytes.size() - pos - 12) break;  // the chunk runs past the end
    const auto crc = static_cast<std::uint32_t>(crc32(0L, p + pos + 4, length + 4));  // over type and data
    if (crc != BigEndian32(p + pos + 8 + length)) {
      throw Error(path + ": corrupt PNG (CRC error in its " + type + " chunk)");
    }
    if (type == "IEND") return;
    pos += 12 + length;
  }
  throw Error(path + ": truncated PNG (the file ends before its IEND chunk)");
}

/// The file's bytes, checked for truncation where the format allows it cheaply.
std::string ReadImageBytes(const std::string& path) {
  if (!std::filesystem::exists(path)) throw Error(path + ": image file not found");
  std::string bytes = ReadTextFile(path);
  if (IsPng(bytes.data(), bytes.size())) CheckPng(bytes, path);
  // JPEG: a file cut short lacks the end-of-image marker near its end (some writers pad after
  // it); libjpeg would only warn and decode the rest as grey.
  if (IsJpeg(bytes.data(), bytes.size())) {
    const std::size_t tail = bytes.size() > 1024 ? bytes.size() - 1024 : 2;
    if (bytes.find("\xff\xd9", tail) == std::string::npos) throw Error(path + ": truncated JPEG (no end-of-image marker)");
  }
  return bytes;
}

/// A one-channel PNG of `bit_depth` as stored, or an error saying what the file holds.
StoredPng ReadOneChannelPng(const std::string& path, int bit_depth, const char* expected) {
  const std::string bytes = ReadImageBytes(path);
  StoredPng png = DecodePngAsStored(bytes.data(), bytes.size(), path);
  if (png.channels != 1 || png.bit_depth != bit_depth) {
    throw Error(path + ": expected " + expected + ", found " + std::to_string(png.channels) + " channel(s) of " +
                std::to_string(png.bit_depth) + " bits");
  }
  return png;
}

/// Image files are written as PNG: a name that promises another format is refused before any
/// work.
void RequirePngName(const std::string& path) {
  const std::string ext = std::filesystem::path(path).extension().string();
  if (ext != ".png" && ext != ".PNG") throw Error(path + ": images are written as PNG (name the file .png)");
}

}  // namespace

ImageU8 ReadGreyImage(const std::string& path) {
  const std::string bytes = ReadImageBytes(path);
  return DecodeGrey(bytes.data(), bytes.size(), path);
}

ImageU8 ReadLabelImage(const std::string& path) {
  return ReadOneChannelPng(path, 8, "an 8-bit single-channel label image").u8;
}

ImageU16 ReadImageU16(const std::string& path) {
  return ReadOneChannelPng(path, 16, "a 16-bit single-channel image").u16;
}

void WriteImage(const ImageU8& image, const std::string& path) {
  RequirePngName(path);
  WritePng(image, path);
}

void WriteImage(const ImageU16& image, const std::string& path) {
  RequirePngName(path);
  WriteFileBytes(EncodePng(image, 1, path), path);
}

void WriteImage(const ImageRgb& image, const std::string& path) {
  RequirePngName(path);
  WritePng(image, path);
}

void WriteImageCompact(const ImageRgb& image, const std::string& path) {
  RequirePngName(path);
  WriteFileBytes(EncodePng(image, 9, path), path);  // zlib's strongest: pictures for people
}

}  // namespace ssta
