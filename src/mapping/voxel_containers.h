#pragma once

// Private: flat containers of voxels keyed by their Morton code (TravOcTree::MortonCode).
// InsertFrame keeps them from frame to frame, so that a frame allocates nothing once they have
// grown.

#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "mapping/trav_octree.h"

namespace ssta::internal {

/// Hash of a Morton code (its low bits alone cluster).
struct CodeHash {
  std::size_t operator()(std::uint64_t code) const {
    return static_cast<std::size_t>((code * 0x9E3779B97F4A7C15ull) >> 16);
  }
};

/// A flat open-addressing set of Morton codes (48 bits, so all ones never occurs): the free
/// voxels of a frame whose rays leave the FreeBitmap's box (rare), or of every ray when the box
/// is too large for a bitmap.
class CodeSet {
 public:
  CodeSet() { slots_.assign(1024, kEmpty); }
  /// Empties the set, keeping its capacity.
  void Clear() {
    if (size_ == 0) return;
    std::fill(slots_.begin(), slots_.end(), kEmpty);
    size_ = 0;
  }
  void Insert(std::uint64_t code) {
    if (2 * (size_ + 1) > slots_.size()) Grow();
    InsertNew(code);
  }
  std::size_t size() const { return size_; }
  template <typename F>
  void ForEach(F&& f) const {
    for (const std::uint64_t code : slots_) {
      if (code != kEmpty) f(code);
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  void InsertNew(std::uint64_t code) {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = CodeHash{}(code) & mask;; i = (i + 1) & mask) {
      if (slots_[i] == code) return;
      if (slots_[i] == kEmpty) {
        slots_[i] = code;
        ++size_;
        return;
      }
    }
  }
  void Grow() {
    std::vector<std::uint64_t> old(2 * slots_.size(), kEmpty);
    old.swap(slots_);
    size_ = 0;
    for (const std::uint64_t code : old) {
      if (code != kEmpty) InsertNew(code);
    }
  }
  std::vector<std::uint64_t> slots_;
  std::size_t size_ = 0;
};

/// The voxels of one frame's points: Morton code -> index of the voxel's accumulator among the
/// frame's in-range hits and among its far points (-1: none). Open addressing, flat, reused
/// from frame to frame (one probe per point instead of an unordered_map node per voxel).
class VoxelIndex {
 public:
  struct Entry {
    std::uint64_t code;
    std::int32_t hit;
    std::int32_t far;
  };
  VoxelIndex() { slots_.assign(1024, Entry{kEmpty, -1, -1}); }
  /// Empties the index, keeping its capacity.
  void Clear() {
    if (size_ == 0) return;
    std::fill(slots_.begin(), slots_.end(), Entry{kEmpty, -1, -1});
    size_ = 0;
  }
  /// The entry of `code`, created (both indices -1) if missing. Valid until the next call.
  Entry& FindOrInsert(std::uint64_t code) {
    if (2 * (size_ + 1) > slots_.size()) Grow();
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = CodeHash{}(code) & mask;; i = (i + 1) & mask) {
      if (slots_[i].code == code) return slots_[i];
      if (slots_[i].code == kEmpty) {
        slots_[i].code = code;
        ++size_;
        return slots_[i];
      }
    }
  }
  /// The entry of `code`, or null.
  const Entry* Find(std::uint64_t code) const {
    const std::size_t mask = slots_.size() - 1;
    for (std::size_t i = CodeHash{}(code) & mask;; i = (i + 1) & mask) {
      if (slots_[i].code == code) return &slots_[i];
      if (slots_[i].code == kEmpty) return nullptr;
    }
  }

 private:
  static constexpr std::uint64_t kEmpty = ~std::uint64_t{0};
  void Grow() {
    std::vector<Entry> old(2 * slots_.size(), Entry{kEmpty, -1, -1});
    old.swap(slots_);
    const std::size_t mask = slots_.size() - 1;
    for (const Entry& e : old) {
      if (e.code == kEmpty) continue;
      std::size_t i = CodeHash{}(e.code) & mask;
      while (slots_[i].code != kEmpty) i = (i + 1) & mask;
      slots_[i] = e;
    }
  }
  std::vector<Entry> slots_;
  std::size_t size_ = 0;
};

/// One bit per voxel of a key box (x fastest): the free voxels of a frame whose rays stay in
/// the box. Setting a bit is one read-modify-write near the ray's previous voxel, where a hash
/// set probes a random slot of a table larger than the cache. All bits are zero between frames.
class FreeBitmap {
 public:
  /// Largest box given a bitmap [voxels] (8 MiB of bits); larger boxes use a CodeSet.
  static constexpr std::uint64_t kMaxVoxels = std::uint64_t{1} << 26;

  /// Takes the box [lo, hi] (inclusive keys); false (and no box) when it holds more than
  /// kMaxVoxels voxels.
  bool Reset(const std::array<int, 3>& lo, const std::array<int, 3>& hi) {
    std::uint64_t voxels = 1;
    std::array<std::uint32_t, 3> size{};
    for (int i = 0; i < 3; ++i) {
      size[i] = static_cast<std::uint32_t>(hi[i] - lo[i] + 1);
      voxels *= size[i];
    }
    if (voxels > kMaxVoxels) return false;
    lo_ = lo;
    size_ = size;
    const std::size_t words = static_cast<std::size_t>((voxels + 63) / 64);
    if (words_.size() < words) words_.resize(words, 0);
    used_words_ = words;
    return true;
  }
  /// Sets the bit of key (x, y, z); false when the key lies outside the box.
  bool Set(const int* k) {
    std::uint32_t index;
    if (!Index(k, &index)) return false;
    words_[index >> 6] |= std::uint64_t{1} << (index & 63);
    return true;
  }
  /// Clears the bit of `key` if it lies in the box.
  void Unset(const octomap::OcTreeKey& key) {
    const int k[3] = {key[0], key[1], key[2]};
    std::uint32_t index;
    if (Index(k, &index)) words_[index >> 6] &= ~(std::uint64_t{1} << (index & 63));
  }
  /// Calls f(Morton code) for each set bit and clears the bits.
  template <typename F>
  void Drain(F&& f) {
    for (std::size_t w = 0; w < used_words_; ++w) {
      std::uint64_t bits = words_[w];
      if (bits == 0) continue;
      words_[w] = 0;
      while (bits != 0) {
        // < kMaxVoxels = 2^26: 32-bit divisions (half the latency of 64-bit ones).
        const auto index = static_cast<std::uint32_t>(64 * w + static_cast<unsigned>(__builtin_ctzll(bits)));
        bits &= bits - 1;
        const std::uint32_t yz = index / size_[0];
        const octomap::OcTreeKey key(static_cast<octomap::key_type>(lo_[0] + static_cast<int>(index % size_[0])),
                                     static_cast<octomap::key_type>(lo_[1] + static_cast<int>(yz % size_[1])),
                                     static_cast<octomap::key_type>(lo_[2] + static_cast<int>(yz / size_[1])));
        f(TravOcTree::MortonCode(key));
      }
    }
  }
  /// Zeroes every bit (after an exception left some set).
  void ClearAll() { std::fill(words_.begin(), words_.end(), 0); }
  /// Sets the bits set in `other`, whose box must be this one's, and zeroes `other`'s.
  void TakeBitsOf(FreeBitmap* other) {
    for (std::size_t w = 0; w < used_words_; ++w) {
      words_[w] |= other->words_[w];
      other->words_[w] = 0;
    }
  }

 private:
  bool Index(const int* k, std::uint32_t* index) const {
    const auto x = static_cast<std::uint32_t>(k[0] - lo_[0]);
    const auto y = static_cast<std::uint32_t>(k[1] - lo_[1]);
    const auto z = static_cast<std::uint32_t>(k[2] - lo_[2]);
    if (x >= size_[0] || y >= size_[1] || z >= size_[2]) return false;
    *index = x + size_[0] * (y + size_[1] * z);
    return true;
  }
  std::vector<std::uint64_t> words_;
  std::size_t used_words_ = 0;
  std::array<int, 3> lo_{};
  std::array<std::uint32_t, 3> size_{};
};

/// Sorts (Morton code, payload) pairs by code: LSD radix sort on the 48 bits, 4 x 12.
/// `scratch` is working space (any content).
template <typename T>
void SortByCode(std::vector<std::pair<std::uint64_t, T>>* items, std::vector<std::pair<std::uint64_t, T>>* scratch_items) {
  constexpr int kBits = 12;
  constexpr std::size_t kBuckets = std::size_t{1} << kBits;
  std::vector<std::pair<std::uint64_t, T>>& scratch = *scratch_items;
  scratch.resize(items->size());
  std::array<std::size_t, kBuckets> start;
  for (int pass = 0; pass < 48 / kBits; ++pass) {
    const int shift = pass * kBits;
    std::fill(start.begin(), start.end(), 0);
    for (const auto& item : *items) ++start[(item.first >> shift) & (kBuckets - 1)];
    std::size_t sum = 0;
    for (std::size_t& s : start) sum += std::exchange(s, sum);
    for (const auto& item : *items) scratch[start[(item.first >> shift) & (kBuckets - 1)]++] = item;
    items->swap(scratch);
  }
}

}  // namespace ssta::internal
