#pragma once

// Helpers for the eval tests: a temporary folder that removes itself, and builders for tiny
// label images and grids written in the layouts the scorers read.

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <initializer_list>
#include <string>
#include <vector>

#include "temp_dir.h"
#include "ssta/core/image.h"
#include "ssta/files/file_util.h"
#include "ssta/io/image_io.h"

namespace ssta::test {

/// The suite-wide temporary folder that removes itself (tests/temp_dir.h).
using TempDir = ::ssta::testing::TempDir;

/// An image from rows of values (all rows the same length), row 0 first.
inline ImageU8 MakeLabels(std::initializer_list<std::initializer_list<int>> rows) {
  std::vector<std::uint8_t> values;
  std::size_t width = 0;
  for (const auto& row : rows) {
    if (values.empty()) width = row.size();
    SSTA_CHECK(row.size() == width, "MakeLabels: rows differ in length");
    for (const int value : row) values.push_back(static_cast<std::uint8_t>(value));
  }
  ImageU8 image(static_cast<int>(width), static_cast<int>(rows.size()));
  for (std::size_t i = 0; i < values.size() && i < image.size(); ++i) image[i] = values[i];
  return image;
}

/// Writes `text` to `path`, creating parent folders.
inline void WriteText(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path) << text;
}

/// Writes a label PNG, creating parent folders.
inline void WriteLabels(const std::string& path, const ImageU8& labels) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  WriteImage(labels, path);
}

/// map_server style YAML as `ssta export` writes it (origin = lower-left corner).
inline std::string GridYaml(const std::string& image, double resolution, double origin_x,
                            double origin_y) {
  return "image: " + image + "\nresolution: " + std::to_string(resolution) + "\norigin: [" +
         std::to_string(origin_x) + ", " + std::to_string(origin_y) +
         ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
}

}  // namespace ssta::test
