#include "bags/chunk_decompression.h"

#include <algorithm>
#include <memory>

#include <lz4frame.h>
#include <zstd.h>

#include "ssta/core/error.h"

namespace ssta::internal {
namespace {

constexpr std::size_t kFirstOutputBytes = 64 * 1024;
// rosbag2 writes chunks of about 1 MB; one message alone makes a larger one (a 4K RGB image is
// 25 MB, a dense point cloud 64 MB), never a quarter of a gigabyte. Larger announcements are
// refused before any memory is taken for them; the bound also keeps a hostile zstd stream of
// run-length blocks (4 bytes per 128 KB) from filling the memory.

/// The output buffer's next size: starts near a typical ratio, doubles, never passes `limit`.
std::size_t GrownSize(std::size_t current, std::size_t limit, std::size_t compressed_size) {
  const std::size_t wanted =
      current == 0 ? std::max(kFirstOutputBytes, compressed_size * 4) : current * 2;
  return std::min(wanted, limit);
}

/// Runs `step` until the input is consumed and the last frame has ended. `step(out, out_size,
/// &written, &consumed)` decompresses into `out` and returns 0 at a frame's end, otherwise
/// nonzero; it throws on corrupt data.
template <typename Step>
std::vector<std::uint8_t> Drain(Step&& step, std::size_t size, std::uint64_t expected,
                                const std::string& where, const char* codec) {
  // One byte of room past the announced size reveals a stream that is longer than announced.
  const std::size_t limit = static_cast<std::size_t>(expected) + 1;
  std::vector<std::uint8_t> out;
  std::size_t produced = 0;
  std::size_t consumed = 0;
  for (;;) {
    if (produced == out.size()) out.resize(GrownSize(out.size(), limit, size));
    const std::size_t room = out.size() - produced;
    std::size_t written = 0;
    std::size_t used = 0;
    const std::size_t hint = step(out.data() + produced, room, consumed, &written, &used);
    produced += written;
    consumed += used;
    if (produced > expected) {
      throw Error(where + ": " + codec + " data decompresses to more than the " + std::to_string(expected) +
                  " bytes the chunk announces");
    }
    if (hint == 0 && consumed == size) break;  // the last frame ended with the input
    if (written < room && used == 0 && written == 0) {
      throw Error(where + ": " + codec + " data ends in the middle of a frame");
    }
    if (consumed == size && written < room && hint != 0) {
      throw Error(where + ": " + codec + " data ends in the middle of a frame");
    }
  }
  if (produced != expected) {
    throw Error(where + ": " + codec + " data decompresses to " + std::to_string(produced) + " bytes, the chunk announces " +
                std::to_string(expected));
  }
  out.resize(produced);
  return out;
}

std::vector<std::uint8_t> DecompressZstd(const std::uint8_t* data, std::size_t size, std::uint64_t expected,
                                         const std::string& where) {
  std::unique_ptr<ZSTD_DCtx, decltype(&ZSTD_freeDCtx)> ctx(ZSTD_createDCtx(), &ZSTD_freeDCtx);
  if (!ctx) throw Error(where + ": cannot create a zstd decoder");
  auto step = [&](std::uint8_t* out, std::size_t room, std::size_t consumed, std::size_t* written,
                  std::size_t* used) {
    ZSTD_inBuffer in{data + consumed, size - consumed, 0};
    ZSTD_outBuffer ob{out, room, 0};
    const std::size_t ret = ZSTD_decompressStream(ctx.get(), &ob, &in);
    if (ZSTD_isError(ret)) throw Error(where + ": corrupt zstd data (" + ZSTD_getErrorName(ret) + ")");
    *written = ob.pos;
    *used = in.pos;
    return ret;
  };
  return Drain(step, size, expected, where, "zstd");
}

std::vector<std::uint8_t> DecompressLz4(const std::uint8_t* data, std::size_t size, std::uint64_t expected,
                                        const std::string& where) {
  LZ4F_dctx* raw = nullptr;
  if (LZ4F_isError(LZ4F_createDecompressionContext(&raw, LZ4F_VERSION))) {
    throw Error(where + ": cannot create an lz4 decoder");
  }
  std::unique_ptr<LZ4F_dctx, decltype(&LZ4F_freeDecompressionContext)> ctx(raw, &LZ4F_freeDecompressionContext);
  auto step = [&](std::uint8_t* out, std::size_t room, std::size_t consumed, std::size_t* written,
                  std::size_t* used) {
    std::size_t dst = room;
    std::size_t src = size - consumed;
    const std::size_t ret = LZ4F_decompress(ctx.get(), out, &dst, data + consumed, &src, nullptr);
    if (LZ4F_isError(ret)) throw Error(where + ": corrupt lz4 data (" + LZ4F_getErrorName(ret) + ")");
    *written = dst;
    *used = src;
    return ret;
  };
  return Drain(step, size, expected, where, "lz4");
}

}  // namespace

std::vector<std::uint8_t> DecompressChunk(const std::string& compression, const std::uint8_t* data,
                                          std::size_t size, std::uint64_t uncompressed_size,
                                          const std::string& where) {
  if (uncompressed_size > kMaxChunkBytes) {
    throw Error(where + ": the chunk announces " + std::to_string(uncompressed_size) +
                " bytes uncompressed, more than the 256 MiB this reader accepts");
  }
  if (compression.empty()) {
    if (size != uncompressed_size) {
      throw Error(where + ": uncompressed chunk holds " + std::to_string(size) + " bytes, its header announces " +
                  std::to_string(uncompressed_size));
    }
    return std::vector<std::uint8_t>(data, data + size);
  }
  if (compression == "zstd") return DecompressZstd(data, size, uncompressed_size, where);
  if (compression == "lz4") return DecompressLz4(data, size, uncompressed_size, where);
  throw Error(where + ": compression '" + compression + "' is not supported (none, zstd or lz4)");
}

}  // namespace ssta::internal
