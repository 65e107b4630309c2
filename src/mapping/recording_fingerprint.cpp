#include "ssta/mapping/recording_fingerprint.h"

#include <algorithm>
#include <cinttypes>
#include <cstdio>
#include <set>
#include <utility>

namespace ssta {
namespace {

constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;
constexpr std::uint64_t kFnvPrime = 1099511628211ull;

std::uint64_t Fnv1a(std::uint64_t h, const void* data, std::size_t n) {
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) {
    h ^= bytes[i];
    h *= kFnvPrime;
  }
  return h;
}

}  // namespace

void RecordingFingerprint::Add(std::int64_t stamp_ns, std::uint64_t image_hash) {
  stamps_ns.push_back(stamp_ns);
  image_hashes.push_back(image_hash);
}

std::string RecordingFingerprint::Digest() const {
  std::uint64_t h = kFnvOffset;
  for (std::size_t i = 0; i < stamps_ns.size() && i < image_hashes.size(); ++i) {
    // Little-endian bytes, so the digest is the same on every machine.
    for (int b = 0; b < 8; ++b) {
      const unsigned char s = static_cast<unsigned char>(static_cast<std::uint64_t>(stamps_ns[i]) >> (8 * b));
      h = Fnv1a(h, &s, 1);
    }
    for (int b = 0; b < 8; ++b) {
      const unsigned char s = static_cast<unsigned char>(image_hashes[i] >> (8 * b));
      h = Fnv1a(h, &s, 1);
    }
  }
  char text[32];
  std::snprintf(text, sizeof(text), "fnv1a64:%016" PRIx64, h);
  return text;
}

SharedFrames FramesShared(const RecordingFingerprint& a, const RecordingFingerprint& b) {
  const RecordingFingerprint& small = a.frames() <= b.frames() ? a : b;
  const RecordingFingerprint& large = a.frames() <= b.frames() ? b : a;
  std::set<std::pair<std::int64_t, std::uint64_t>> frames;
  for (std::size_t i = 0; i < small.frames(); ++i) frames.emplace(small.stamps_ns[i], small.image_hashes[i]);
  SharedFrames shared;
  for (std::size_t i = 0; i < large.frames(); ++i) {
    const std::int64_t t = large.stamps_ns[i];
    if (frames.count({t, large.image_hashes[i]}) == 0) continue;
    shared.first_stamp_ns = shared.count == 0 ? t : std::min(shared.first_stamp_ns, t);
    ++shared.count;
  }
  return shared;
}

std::uint64_t SampledImageHash(const ImageU8& image) {
  const std::int32_t size[2] = {image.width(), image.height()};
  std::uint64_t h = Fnv1a(kFnvOffset, size, sizeof(size));
  if (image.empty()) return h;
  const int rows = std::min(16, image.height());
  for (int k = 0; k < rows; ++k) {
    const int v = rows == 1 ? 0 : static_cast<int>(static_cast<long long>(k) * (image.height() - 1) / (rows - 1));
    h = Fnv1a(h, &image(v, 0), static_cast<std::size_t>(image.width()));
  }
  return h;
}

}  // namespace ssta
