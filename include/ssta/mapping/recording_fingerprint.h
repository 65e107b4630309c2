#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "ssta/core/image.h"

namespace ssta {

/// The frames of one recording that a map fused: their times and a hash of their images. It
/// tells a recording fused twice (under another name, every second frame of it, from a folder
/// or from a bag of it) from another recording, also one rendered or recorded at the same
/// times (docs/fleet.md).
struct RecordingFingerprint {
  std::string sequence;  ///< the name the recording was fused under (MapMetadata::sequences)
  /// Per fused frame, in fusion order: the left image's timestamp [ns] ...
  std::vector<std::int64_t> stamps_ns;
  /// ... and SampledImageHash of its decoded grey left image (the same for a folder and a bag
  /// that hold the same pixels).
  std::vector<std::uint64_t> image_hashes;

  /// Appends a fused frame.
  void Add(std::int64_t stamp_ns, std::uint64_t image_hash);
  std::size_t frames() const { return stamps_ns.size(); }
  /// FNV-1a 64 over the frames' (stamp, image hash) pairs in order, "fnv1a64:<16 hex digits>":
  /// one name for the frames, equal when they are.
  std::string Digest() const;
};

/// The frames two fingerprints share: same timestamp and same image hash.
struct SharedFrames {
  std::size_t count = 0;            ///< frames both hold
  std::int64_t first_stamp_ns = 0;  ///< the earliest of them [ns]; 0 when count is 0
};

/// The frames `a` and `b` share (the overlap rule of merge-maps and build-map --resume: a
/// recording overlaps a map when it shares one frame with a recording the map holds).
SharedFrames FramesShared(const RecordingFingerprint& a, const RecordingFingerprint& b);

/// A 64-bit hash (FNV-1a) of an image's decoded pixels: its width, height and 16 rows evenly
/// spaced from the first to the last (every row of a smaller image). Costs ~16 us at 752x480,
/// against milliseconds to decode it. Equal pixels give equal hashes whatever the container.
std::uint64_t SampledImageHash(const ImageU8& image);

}  // namespace ssta
