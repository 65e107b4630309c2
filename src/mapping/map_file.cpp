// Save and Load of TraversabilityMap. The layout (maps/README.md) is one OctoMap .ot file:
//
//   # Octomap OcTree file                      <- OctoMap's required first line
//   # SSTA traversability map ...              <- comment
//   #@ssta format_version: 1                   <- metadata, YAML, one line per comment line
//   #@ssta ...
//   id SstaTravOcTree
//   size <nodes>
//   res <resolution>
//   data
//   <OctoMap binary node stream>               <- TravNode::writeData per node, depth first
//   \n# ssta-map-end bytes <N> fnv1a64 <hash>\n  <- trailer: N bytes before it, their hash
//
// OctoMap's reader skips '#' lines in the header and ignores bytes after the tree, so the file
// stays a valid .ot file; the trailer lets Load reject truncated or damaged files before
// OctoMap's recursive reader (which does not check its stream) touches them.

#include <algorithm>
#include <cctype>
#include <cinttypes>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <sstream>
#include <streambuf>
#include <vector>

#include <yaml-cpp/yaml.h>

#include "ssta/files/yaml_reader.h"
#include "mapping/map_file_reader.h"
#include "mapping/map_impl.h"
#include "ssta/core/error.h"
#include "ssta/core/rigid_transform.h"
#include "ssta/files/file_util.h"

#ifndef SSTA_VERSION
#define SSTA_VERSION "unknown"
#endif

namespace ssta {
namespace {

constexpr char kFirstLine[] = "# Octomap OcTree file";
constexpr char kMetaPrefix[] = "#@ssta";
constexpr char kTrailerTag[] = "\n# ssta-map-end bytes ";
constexpr std::uint64_t kFnvOffset = 14695981039346656037ull;
constexpr std::uint64_t kFnvPrime = 1099511628211ull;

std::uint64_t Fnv1a(std::uint64_t h, const char* data, std::size_t n) {
  for (std::size_t i = 0; i < n; ++i) {
    h ^= static_cast<unsigned char>(data[i]);
    h *= kFnvPrime;
  }
  return h;
}

/// Forwards everything to `sink` while counting bytes and hashing them (FNV-1a, 64 bit), in
/// blocks of kBlock bytes: a map is written in millions of small pieces.
class HashingStreamBuf : public std::streambuf {
 public:
  explicit HashingStreamBuf(std::streambuf* sink) : sink_(sink), block_(kBlock) {
    setp(block_.data(), block_.data() + block_.size());
  }
  HashingStreamBuf(const HashingStreamBuf&) = delete;
  HashingStreamBuf& operator=(const HashingStreamBuf&) = delete;
  /// Bytes and hash of everything written so far (the block not yet forwarded included).
  std::uint64_t bytes() const { return bytes_ + static_cast<std::uint64_t>(pptr() - pbase()); }
  std::uint64_t hash() const { return Fnv1a(hash_, pbase(), static_cast<std::size_t>(pptr() - pbase())); }

 protected:
  int_type overflow(int_type c) override {
    if (!Forward()) return traits_type::eof();
    if (traits_type::eq_int_type(c, traits_type::eof())) return traits_type::not_eof(c);
    *pptr() = traits_type::to_char_type(c);
    pbump(1);
    return c;
  }
  int sync() override { return Forward() ? sink_->pubsync() : -1; }

 private:
  static constexpr std::size_t kBlock = 1 << 16;
  /// Hashes the block and hands it to the sink; false when the sink takes less.
  bool Forward() {
    const std::streamsize n = pptr() - pbase();
    hash_ = Fnv1a(hash_, pbase(), static_cast<std::size_t>(n));
    bytes_ += static_cast<std::uint64_t>(n);
    const bool ok = sink_->sputn(pbase(), n) == n;
    setp(block_.data(), block_.data() + block_.size());
    return ok;
  }

  std::streambuf* sink_;
  std::vector<char> block_;
  std::uint64_t bytes_ = 0;
  std::uint64_t hash_ = kFnvOffset;
};

/// Read-only stream buffer over memory (no copy of the file).
class MemoryStreamBuf : public std::streambuf {
 public:
  MemoryStreamBuf(const char* begin, const char* end) {
    char* b = const_cast<char*>(begin);
    setg(b, b, const_cast<char*>(end));
  }
  std::size_t consumed() const { return static_cast<std::size_t>(gptr() - eback()); }
};

/// Writes every field of `fields` whose value is not what old files meant by leaving it out.
template <class O>
void EmitFields(const O& options, const OptionFields<O>& fields, YAML::Emitter* out) {
  for (const OptionField<O>& f : fields) {
    const OptionValue value = f.get(options);
    if (f.absent_means && value == *f.absent_means) continue;  // files made before the key stay as they were
    *out << YAML::Key << f.key << YAML::Value << FormatOptionValue(value, f.kind);
  }
}

/// Reads every field of `fields`; a key left out takes what old files meant by leaving it out,
/// and is an error when the key was always written.
template <class O>
void ReadFields(internal::YamlSection& section, const OptionFields<O>& fields, O* options) {
  for (const OptionField<O>& f : fields) {
    if (!section.Has(f.key)) {
      if (!f.absent_means) throw Error(section.Name(f.key) + ": missing key");
      f.set(options, *f.absent_means);
    }
  }
  internal::ReadOptions(section, fields, options);
}

std::string HashText(std::uint64_t hash) {
  char text[17];
  std::snprintf(text, sizeof(text), "%016" PRIx64, hash);
  return text;
}

/// Emits `key` with the first three rows of `t` (4x4 row-major; the last row is 0 0 0 1) as
/// one flow list of 12 numbers.
void EmitMountMatrix(const char* key, const Eigen::Isometry3d& t, YAML::Emitter* out) {
  *out << YAML::Key << key << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) *out << ShortestDecimal(t.matrix()(i, j));
  }
  *out << YAML::EndSeq;
}

/// Emits the refined_mount section: the configured and the refined body_T_cam0.
void EmitRefinedMount(const RefinedMount& mount, YAML::Emitter* out) {
  *out << YAML::Key << "refined_mount" << YAML::Value << YAML::BeginMap;
  EmitMountMatrix("configured_body_T_cam0", mount.configured, out);
  EmitMountMatrix("refined_body_T_cam0", mount.refined, out);
  *out << YAML::EndMap;
}

/// Emits the notes section, one quoted note per line.
void EmitNotes(const std::vector<std::string>& notes, YAML::Emitter* out) {
  *out << YAML::Key << "notes" << YAML::Value << YAML::BeginSeq;
  for (const std::string& note : notes) *out << YAML::DoubleQuoted << note;
  *out << YAML::EndSeq;
}

/// Emits the merged_from section, one flow map per source map.
void EmitMergedFrom(const std::vector<MapSource>& sources, YAML::Emitter* out) {
  *out << YAML::Key << "merged_from" << YAML::Value << YAML::BeginSeq;
  for (const MapSource& source : sources) {
    *out << YAML::Flow << YAML::BeginMap;
    *out << YAML::Key << "file" << YAML::Value << YAML::DoubleQuoted << source.file;
    *out << YAML::Key << "checksum" << YAML::Value << source.checksum;
    *out << YAML::Key << "sequences" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const std::string& name : source.sequences) *out << YAML::DoubleQuoted << name;
    *out << YAML::EndSeq;
    *out << YAML::Key << "frames_inserted" << YAML::Value << source.frames_inserted;
    *out << YAML::Key << "software_version" << YAML::Value << YAML::DoubleQuoted << source.software_version;
    *out << YAML::EndMap;
  }
  *out << YAML::EndSeq;
}

/// Emits the recordings section, one flow map per recording: its frames' stamps and their
/// image hashes, 16 hex digits each, in one string.
void EmitRecordings(const std::vector<RecordingFingerprint>& recordings, YAML::Emitter* out) {
  *out << YAML::Key << "recordings" << YAML::Value << YAML::BeginSeq;
  for (const RecordingFingerprint& r : recordings) {
    std::string hashes;
    hashes.reserve(16 * r.image_hashes.size());
    for (const std::uint64_t h : r.image_hashes) hashes += HashText(h);
    *out << YAML::Flow << YAML::BeginMap;
    *out << YAML::Key << "sequence" << YAML::Value << YAML::DoubleQuoted << r.sequence;
    *out << YAML::Key << "frames" << YAML::Value << r.frames();
    *out << YAML::Key << "fingerprint" << YAML::Value << r.Digest();
    *out << YAML::Key << "stamps_ns" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const std::int64_t t : r.stamps_ns) *out << t;
    *out << YAML::EndSeq;
    *out << YAML::Key << "image_hashes" << YAML::Value << YAML::DoubleQuoted << hashes;
    *out << YAML::EndMap;
  }
  *out << YAML::EndSeq;
}

/// Emits the sensor_path section: x, y, z of each kept origin, to the millimetre (the path is
/// for pictures and reports), in one flow list.
void EmitSensorPath(const std::vector<Eigen::Vector3d>& path, YAML::Emitter* out) {
  *out << YAML::Key << "sensor_path" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const Eigen::Vector3d& p : path) {
    for (int i = 0; i < 3; ++i) *out << ShortestDecimal(std::round(p[i] * 1000.0) / 1000.0);
  }
  *out << YAML::EndSeq;
}

/// The metadata of `map` as YAML: the always written keys, then each optional section the map
/// has. Doubles go out as their shortest exact decimal text (plain scalars, read back as doubles).
std::string MetadataYaml(const TraversabilityMap& map) {
  const MapMetadata& m = map.metadata();
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "format_version" << YAML::Value << kMapFormatVersion;
  out << YAML::Key << "software_version" << YAML::Value << SSTA_VERSION;
  out << YAML::Key << "frames_inserted" << YAML::Value << map.frames_inserted();
  out << YAML::Key << "last_timestamp_ns" << YAML::Value << map.last_timestamp_ns();
  out << YAML::Key << "map_options" << YAML::Value << YAML::BeginMap;
  EmitFields(map.options(), MapOptions::Fields(), &out);
  out << YAML::EndMap;
  out << YAML::Key << "vehicle" << YAML::Value << YAML::BeginMap;
  EmitFields(m.vehicle, VehicleOptions::Fields(), &out);
  out << YAML::EndMap;
  out << YAML::Key << "calibration_summary" << YAML::Value << YAML::DoubleQuoted
      << m.calibration_summary;
  out << YAML::Key << "sequences" << YAML::Value << YAML::Flow << YAML::BeginSeq;
  for (const std::string& s : m.sequences) out << YAML::DoubleQuoted << s;
  out << YAML::EndSeq;
  if (m.refined_mount) EmitRefinedMount(*m.refined_mount, &out);
  if (!m.world_frame.empty()) out << YAML::Key << "world_frame" << YAML::Value << YAML::DoubleQuoted << m.world_frame;
  if (!m.notes.empty()) EmitNotes(m.notes, &out);
  if (!m.merged_from.empty()) EmitMergedFrom(m.merged_from, &out);
  if (!m.recordings.empty()) EmitRecordings(m.recordings, &out);
  if (!map.sensor_path().empty()) EmitSensorPath(map.sensor_path(), &out);
  out << YAML::EndMap;
  if (!out.good()) throw InternalError(std::string("map metadata YAML: ") + out.GetLastError());
  return out.c_str();
}

/// What the text header of a map file says.
struct Header {
  std::string id;
  std::uint64_t size = 0;
  double resolution = 0.0;
  std::string metadata_yaml;
  std::size_t data_begin = 0;  // offset of the binary node stream
};

bool StartsWith(const std::string& s, const char* prefix) { return s.rfind(prefix, 0) == 0; }

Header ParseHeader(const std::string& bytes, const std::string& path) {
  const std::size_t first_end = bytes.find('\n');
  if (first_end == std::string::npos || !StartsWith(bytes, kFirstLine)) {
    throw Error(path + ": not an OctoMap .ot file (the first line is not '" + kFirstLine + "')");
  }
  Header header;
  std::size_t pos = first_end + 1;
  bool have_data = false, have_size = false, have_res = false;
  while (pos < bytes.size()) {
    std::size_t end = bytes.find('\n', pos);
    if (end == std::string::npos) break;
    std::string line = bytes.substr(pos, end - pos);
    pos = end + 1;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (StartsWith(line, kMetaPrefix)) {
      std::string text = line.substr(sizeof(kMetaPrefix) - 1);
      if (!text.empty() && text[0] == ' ') text.erase(0, 1);
      header.metadata_yaml += text + '\n';
      continue;
    }
    if (line.empty() || line[0] == '#') continue;
    std::istringstream tokens(line);
    std::string keyword;
    tokens >> keyword;
    if (keyword == "data") {
      have_data = true;
      break;
    }
    if (keyword == "id") {
      tokens >> header.id;
    } else if (keyword == "size") {
      have_size = static_cast<bool>(tokens >> header.size);
    } else if (keyword == "res") {
      have_res = static_cast<bool>(tokens >> header.resolution);
    }
  }
  if (!have_data) throw Error(path + ": truncated or corrupt map (the OctoMap header has no 'data' line)");
  if (header.id.empty()) header.id = "OcTree";  // OctoMap's default for old files
  if (header.id != internal::TravOcTree::kTreeType) {
    throw Error(path + ": OctoMap tree type '" + header.id +
                "' is not an SSTA traversability map (expected '" +
                internal::TravOcTree::kTreeType + "', as written by ssta build-map)");
  }
  if (!have_size || !have_res || !(header.resolution > 0.0)) {
    throw Error(path + ": corrupt map header (missing or bad 'size' or 'res')");
  }
  header.data_begin = pos;
  return header;
}

/// Parses the trailer within `tail`, the file's bytes from offset `tail_offset` to its end,
/// and returns the file offset where it starts (= end of the node stream); `*hash` is the
/// hash it records, 16 hex digits.
std::size_t ParseTrailer(const std::string& tail, std::size_t tail_offset, const std::string& path,
                         std::string* hash) {
  const std::size_t tag = tail.rfind(kTrailerTag);
  const std::string truncated = path + ": truncated or corrupt map (";
  if (tag == std::string::npos) throw Error(truncated + "no end marker; was the save interrupted?)");
  unsigned long long count = 0;
  char hash_text[17] = {0};
  const std::string trailer = tail.substr(tag + sizeof(kTrailerTag) - 1);
  if (std::sscanf(trailer.c_str(), "%llu fnv1a64 %16[0-9a-f]", &count, hash_text) != 2 ||
      count != tail_offset + tag || trailer.empty() || trailer.back() != '\n') {
    throw Error(truncated + "bad end marker)");
  }
  *hash = hash_text;
  return tail_offset + tag;
}

void RequireHash(const std::string& recorded, std::uint64_t computed, const std::string& path, std::string* checksum) {
  if (HashText(computed) != recorded) throw Error(path + ": truncated or corrupt map (checksum mismatch)");
  *checksum = "fnv1a64:" + recorded;
}

/// Checks the trailer and returns the offset where it starts (= end of the node stream);
/// `*checksum` is its hash as "fnv1a64:<hex>".
std::size_t VerifyTrailer(const std::string& bytes, const std::string& path, std::string* checksum) {
  std::string recorded;
  const std::size_t end = ParseTrailer(bytes, 0, path, &recorded);
  RequireHash(recorded, Fnv1a(kFnvOffset, bytes.data(), end), path, checksum);
  return end;
}

/// Checks a node's values as CheckNodeStream does: OctoMap's reader trusts them.
void RequireFinite(const internal::TravNode& node, std::uint64_t index, const std::string& path) {
  const float values[] = {node.getValue(),   node.class_log_odds[0], node.class_log_odds[1],
                          node.class_log_odds[2], node.slope_deg, node.step_m,
                          node.max_step_m,   node.surface_z,      node.surface_weight,
                          node.surface_xy_sigma_m};
  for (const float v : values) {
    if (!std::isfinite(v)) throw Error(path + ": corrupt map (node " + std::to_string(index) + " holds NaN or infinity)");
  }
}

/// Walks the node stream [begin, end) the way OctoMap's reader will (a node's payload, then a
/// byte whose bits say which of its eight children follow, depth first) without recursion,
/// and checks what that reader does not: every node is complete, no node lies deeper than
/// `max_depth`, every payload value is finite, the stream ends exactly at `end` and holds
/// `expected_nodes` nodes. Only then may OctoMap's recursive reader, which trusts its input
/// (a lying stream makes it recurse without bound or read uninitialised bytes), see it.
void CheckNodeStream(const char* begin, const char* end, unsigned max_depth, std::uint64_t expected_nodes,
                     const std::string& path) {
  const std::string corrupt = path + ": corrupt map (";
  MemoryStreamBuf buffer(begin, end);
  std::istream in(&buffer);
  std::vector<int> children_left;  // per open ancestor: children still to read
  std::uint64_t nodes = 0;
  internal::TravNode node;
  const auto read_node = [&](unsigned depth) {
    node.readData(in);
    char children = 0;
    in.read(&children, 1);
    if (!in) throw Error(corrupt + "the node stream ends inside node " + std::to_string(nodes) + ")");
    ++nodes;
    RequireFinite(node, nodes - 1, path);
    const auto bits = static_cast<unsigned char>(children);
    if (bits == 0) return;
    if (depth >= max_depth) throw Error(corrupt + "a node lies deeper than the tree depth)");
    int count = 0;
    for (int i = 0; i < 8; ++i) count += (bits >> i) & 1;
    children_left.push_back(count);
  };
  read_node(0);
  while (!children_left.empty()) {
    if (children_left.back() == 0) {
      children_left.pop_back();
      continue;
    }
    --children_left.back();
    read_node(static_cast<unsigned>(children_left.size()));
  }
  if (buffer.consumed() != static_cast<std::size_t>(end - begin) || nodes != expected_nodes) {
    throw Error(corrupt + "the node stream does not match its header)");
  }
}

/// What the metadata YAML of a map file says.
struct FileMetadata {
  int format_version = 0;
  std::string software_version;
  std::uint64_t frames_inserted = 0;
  std::int64_t last_timestamp_ns = 0;
  MapOptions options;
  MapMetadata metadata;
  std::vector<Eigen::Vector3d> sensor_path;
};

/// The format_version of the metadata `root`, one this build reads.
int ReadFormatVersion(internal::YamlSection& root, const std::string& path) {
  if (!root.Has("format_version")) {
    throw Error(path + ": not an SSTA map (its header has no '#@ssta format_version')");
  }
  const int version = root.Require<int>("format_version");
  if (version > kMapFormatVersion) {
    throw Error(path + ": map format version " + std::to_string(version) +
                " is newer than this ssta reads (" + std::to_string(kMapFormatVersion) +
                "); use a newer ssta");
  }
  if (version < 1) throw Error(root.Name("format_version") + ": must be >= 1");
  return version;
}

/// The map_options section, checked.
MapOptions ReadMapOptions(internal::YamlSection& root, const std::string& path) {
  MapOptions options;
  internal::YamlSection o = root.Child("map_options");
  ReadFields(o, MapOptions::Fields(), &options);
  std::string error;
  if (!options.IsValid(&error)) throw Error(path + ": map_options." + error);
  return options;
}

/// The vehicle section, checked.
VehicleOptions ReadVehicle(internal::YamlSection& root, const std::string& path) {
  VehicleOptions vehicle;
  internal::YamlSection v = root.Child("vehicle");
  ReadFields(v, VehicleOptions::Fields(), &vehicle);
  std::string error;
  if (!vehicle.IsValid(&error)) throw Error(path + ": vehicle." + error);
  return vehicle;
}

/// The rigid transform `key` of the refined_mount section `r`, 12 numbers: the first three
/// rows of the 4x4 row-major matrix.
Eigen::Isometry3d ReadMountMatrix(internal::YamlSection& r, const char* key) {
  if (!r.Has(key)) throw Error(r.Name(key) + ": missing");
  std::vector<double> v;
  r.ReadList(key, &v, 12);
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 4; ++j) t.matrix()(i, j) = v[4 * i + j];
  }
  std::string why;
  if (!IsRigidTransform(t.matrix(), &why)) throw Error(r.Name(key) + ": not a rigid transform: " + why);
  return t;
}

/// The refined_mount section: the configured and the refined body_T_cam0.
RefinedMount ReadRefinedMount(internal::YamlSection& root) {
  internal::YamlSection r = root.Child("refined_mount");
  return RefinedMount{ReadMountMatrix(r, "configured_body_T_cam0"), ReadMountMatrix(r, "refined_body_T_cam0")};
}

/// The merged_from section of the metadata `yaml`: the source maps.
std::vector<MapSource> ReadMergedFrom(const std::string& yaml, const std::string& path,
                                      const internal::YamlSection& root) {
  std::vector<MapSource> sources;
  const YAML::Node list = internal::ParseYaml(yaml, path)["merged_from"];
  if (!list.IsSequence()) throw Error(root.Name("merged_from") + ": must be a list");
  for (std::size_t i = 0; i < list.size(); ++i) {
    internal::YamlSection entry(list[i], path, "merged_from[" + std::to_string(i) + "]");
    MapSource source;
    source.file = entry.Require<std::string>("file");
    source.checksum = entry.Require<std::string>("checksum");
    source.sequences = entry.Require<std::vector<std::string>>("sequences");
    source.frames_inserted = entry.Require<std::uint64_t>("frames_inserted");
    source.software_version = entry.Require<std::string>("software_version");
    sources.push_back(std::move(source));
  }
  return sources;
}

/// One entry of the recordings section, its image hashes and fingerprint checked against its
/// stamps.
RecordingFingerprint ReadRecording(internal::YamlSection& entry) {
  RecordingFingerprint r;
  r.sequence = entry.Require<std::string>("sequence");
  r.stamps_ns = entry.Require<std::vector<std::int64_t>>("stamps_ns");
  const std::string hashes = entry.Require<std::string>("image_hashes");
  const auto frames = entry.Require<std::uint64_t>("frames");
  if (frames != r.stamps_ns.size() || hashes.size() != 16 * r.stamps_ns.size() ||
      hashes.find_first_not_of("0123456789abcdef") != std::string::npos) {
    throw Error(entry.Name("image_hashes") + ": needs 16 hex digits for each of the " +
                std::to_string(r.stamps_ns.size()) + " stamps and 'frames' their count");
  }
  for (std::size_t k = 0; k < hashes.size(); k += 16) {
    r.image_hashes.push_back(std::strtoull(hashes.substr(k, 16).c_str(), nullptr, 16));
  }
  if (entry.Require<std::string>("fingerprint") != r.Digest()) {
    throw Error(entry.Name("fingerprint") + ": does not match its stamps and image hashes");
  }
  return r;
}

/// The recordings section of the metadata `yaml`: the fingerprints of the recordings fused.
std::vector<RecordingFingerprint> ReadRecordings(const std::string& yaml, const std::string& path,
                                                 const internal::YamlSection& root) {
  std::vector<RecordingFingerprint> recordings;
  const YAML::Node list = internal::ParseYaml(yaml, path)["recordings"];
  if (!list.IsSequence()) throw Error(root.Name("recordings") + ": must be a list");
  for (std::size_t i = 0; i < list.size(); ++i) {
    internal::YamlSection entry(list[i], path, "recordings[" + std::to_string(i) + "]");
    recordings.push_back(ReadRecording(entry));
  }
  return recordings;
}

/// The sensor_path section: x, y, z triples, each finite.
std::vector<Eigen::Vector3d> ReadSensorPath(internal::YamlSection& root) {
  std::vector<Eigen::Vector3d> path;
  const auto values = root.Require<std::vector<double>>("sensor_path");
  if (values.size() % 3 != 0) {
    throw Error(root.Name("sensor_path") + ": needs x, y, z triples (" + std::to_string(values.size()) +
                " numbers)");
  }
  for (std::size_t i = 0; i < values.size(); i += 3) {
    const Eigen::Vector3d p(values[i], values[i + 1], values[i + 2]);
    if (!p.allFinite()) throw Error(root.Name("sensor_path") + ": point " + std::to_string(i / 3) + " is not finite");
    path.push_back(p);
  }
  return path;
}

/// Reads the metadata YAML of the map file `path`: the always written keys, then each optional
/// section it has. Throws ssta::Error naming the file and key.
FileMetadata ReadMetadata(const std::string& yaml, const std::string& path) {
  internal::YamlSection root(internal::ParseYaml(yaml, path), path, "");
  FileMetadata out;
  out.format_version = ReadFormatVersion(root, path);
  out.software_version = root.Require<std::string>("software_version");
  out.frames_inserted = root.Require<std::uint64_t>("frames_inserted");
  out.last_timestamp_ns = root.Require<std::int64_t>("last_timestamp_ns");
  out.options = ReadMapOptions(root, path);
  MapMetadata& m = out.metadata;
  m.vehicle = ReadVehicle(root, path);
  m.calibration_summary = root.Require<std::string>("calibration_summary");
  m.sequences = root.Require<std::vector<std::string>>("sequences");
  if (root.Has("refined_mount")) m.refined_mount = ReadRefinedMount(root);
  if (root.Has("world_frame")) m.world_frame = root.Require<std::string>("world_frame");
  if (root.Has("notes")) m.notes = root.Require<std::vector<std::string>>("notes");
  if (root.Has("merged_from")) m.merged_from = ReadMergedFrom(yaml, path, root);
  if (root.Has("recordings")) m.recordings = ReadRecordings(yaml, path, root);
  if (root.Has("sensor_path")) out.sensor_path = ReadSensorPath(root);
  return out;
}

/// The state of a map holding `metadata`, without its tree and file checksum.
std::unique_ptr<internal::MapImpl> ImplWithMetadata(FileMetadata metadata) {
  auto impl = std::make_unique<internal::MapImpl>();
  impl->options = std::move(metadata.options);
  impl->metadata = std::move(metadata.metadata);
  impl->frames_inserted = metadata.frames_inserted;
  impl->last_timestamp_ns = metadata.last_timestamp_ns;
  impl->software_version = std::move(metadata.software_version);
  impl->sensor_path.Assign(std::move(metadata.sensor_path));
  return impl;
}

}  // namespace

void TraversabilityMap::Save(const std::string& path) const {
  const std::string metadata = MetadataYaml(*this);
  const internal::TravOcTree& tree = *impl_->tree;
  WriteFileAtomically(path, [&](const std::string& tmp) {
    std::ofstream file(tmp, std::ios::binary);
    if (!file) throw Error(path + ": cannot open for writing");
    HashingStreamBuf hashing(file.rdbuf());
    std::ostream out(&hashing);
    out << kFirstLine << '\n'
        << "# SSTA traversability map; lines starting with '" << kMetaPrefix
        << "' hold its metadata (YAML), see maps/README.md\n";
    std::istringstream lines(metadata);
    for (std::string line; std::getline(lines, line);) {
      out << kMetaPrefix << (line.empty() ? "" : " ") << line << '\n';
    }
    out << "id " << tree.getTreeType() << '\n'
        << "size " << tree.size() << '\n'
        << "res " << ShortestDecimal(tree.getResolution()) << '\n'
        << "data\n";
    tree.writeData(out);
    out.flush();
    if (!out) throw Error(path + ": write failed (disk full?)");
    char trailer[96];
    std::snprintf(trailer, sizeof(trailer), "%s%" PRIu64 " fnv1a64 %016" PRIx64 "\n", kTrailerTag,
                  hashing.bytes(), hashing.hash());
    file << trailer;
    file.flush();
    if (!file) throw Error(path + ": write failed (disk full?)");
  }, /*remove_stale=*/true);
}

TraversabilityMap TraversabilityMap::Load(const std::string& path) {
  return internal::TraversabilityMapAccess::LoadFromBytes(ReadTextFile(path), path);  // binary-safe; throws naming the file
}

TraversabilityMap internal::TraversabilityMapAccess::LoadFromBytes(const std::string& bytes, const std::string& path) {
  const Header header = ParseHeader(bytes, path);

  // The metadata (and with it the format version) is read before the node stream is trusted.
  FileMetadata metadata = ReadMetadata(header.metadata_yaml, path);
  const int format = metadata.format_version;
  auto impl = ImplWithMetadata(std::move(metadata));
  const std::size_t data_end = VerifyTrailer(bytes, path, &impl->file_checksum);
  if (header.data_begin > data_end) throw Error(path + ": truncated or corrupt map (no node data)");
  if (std::abs(header.resolution - impl->options.resolution_m) > 1e-9 * impl->options.resolution_m) {
    throw Error(path + ": corrupt map (header res " + std::to_string(header.resolution) +
                " differs from map_options.resolution_m)");
  }

  impl->tree = internal::MakeTree(impl->options);
  const internal::ScopedNodeFormat node_format(format);  // the node layout of this file's format
  if (header.size > 0) {
    CheckNodeStream(bytes.data() + header.data_begin, bytes.data() + data_end, impl->tree->getTreeDepth(),
                    header.size, path);
    MemoryStreamBuf buffer(bytes.data() + header.data_begin, bytes.data() + data_end);
    std::istream in(&buffer);
    impl->tree->readData(in);
    if (!in || buffer.consumed() != data_end - header.data_begin ||
        impl->tree->size() != header.size) {
      throw Error(path + ": corrupt map (the node stream does not match its header)");
    }
  } else if (data_end != header.data_begin) {
    throw Error(path + ": corrupt map (node data after an empty tree)");
  }
  return internal::TraversabilityMapAccess::FromImpl(std::move(impl));
}

namespace internal {

/// Reads the node stream [begin, end) of the file through a fixed buffer.
class MapFileReader::LimitedFileBuf : public std::streambuf {
 public:
  LimitedFileBuf(std::ifstream* file, std::uint64_t length) : file_(file), left_(length) {}

 protected:
  int_type underflow() override {
    if (gptr() < egptr()) return traits_type::to_int_type(*gptr());
    if (left_ == 0) return traits_type::eof();
    const auto n = static_cast<std::streamsize>(std::min<std::uint64_t>(left_, sizeof(buffer_)));
    file_->read(buffer_, n);
    if (file_->gcount() != n) return traits_type::eof();
    left_ -= static_cast<std::uint64_t>(n);
    setg(buffer_, buffer_, buffer_ + n);
    return traits_type::to_int_type(buffer_[0]);
  }

 private:
  std::ifstream* file_;
  std::uint64_t left_;
  char buffer_[1 << 16];
};

MapFileReader::MapFileReader(const std::string& path) : path_(path), file_(path, std::ios::binary) {
  if (!file_) throw Error(path + ": cannot open map file");
  file_.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(file_.tellg());
  // Pass 1: the trailer from the file's last bytes, then the hash of everything before it.
  const std::uint64_t tail_size = std::min<std::uint64_t>(size, 128);
  std::string tail(tail_size, '\0');
  file_.seekg(static_cast<std::streamoff>(size - tail_size));
  file_.read(tail.data(), static_cast<std::streamsize>(tail_size));
  std::string recorded;
  const std::uint64_t data_end = ParseTrailer(tail, size - tail_size, path, &recorded);
  file_.seekg(0);
  std::uint64_t hash = kFnvOffset;
  std::vector<char> chunk(1 << 20);
  for (std::uint64_t left = data_end; left > 0;) {
    const auto n = static_cast<std::streamsize>(std::min<std::uint64_t>(left, chunk.size()));
    file_.read(chunk.data(), n);
    if (file_.gcount() != n) throw Error(path + ": read failed");
    hash = Fnv1a(hash, chunk.data(), static_cast<std::size_t>(n));
    left -= static_cast<std::uint64_t>(n);
  }
  std::string file_checksum;
  RequireHash(recorded, hash, path, &file_checksum);

  // Pass 2: the header's lines up to 'data', as Load reads them, then the nodes on demand.
  file_.seekg(0);
  std::string header_text;
  for (std::string line; std::getline(file_, line);) {
    header_text += line + '\n';
    if (line.rfind("data", 0) == 0 && (line.size() == 4 || std::isspace(static_cast<unsigned char>(line[4])))) break;
    if (header_text.size() > data_end) break;
  }
  const Header header = ParseHeader(header_text, path);
  if (header.data_begin > data_end) throw Error(path + ": truncated or corrupt map (no node data)");
  FileMetadata metadata = ReadMetadata(header.metadata_yaml, path);
  format_ = metadata.format_version;
  auto impl = ImplWithMetadata(std::move(metadata));
  impl->file_checksum = std::move(file_checksum);
  if (std::abs(header.resolution - impl->options.resolution_m) > 1e-9 * impl->options.resolution_m) {
    throw Error(path + ": corrupt map (header res " + std::to_string(header.resolution) +
                " differs from map_options.resolution_m)");
  }
  impl->tree = MakeTree(impl->options);
  max_depth_ = impl->tree->getTreeDepth();
  nodes_ = header.size;
  shell_ = TraversabilityMapAccess::FromImpl(std::move(impl));
  file_.clear();
  file_.seekg(static_cast<std::streamoff>(header.data_begin));
  buffer_ = std::make_unique<LimitedFileBuf>(&file_, data_end - header.data_begin);
  stream_ = std::make_unique<std::istream>(buffer_.get());
}

MapFileReader::~MapFileReader() = default;

unsigned char MapFileReader::ReadNode(TravNode* node, unsigned depth) {
  const std::string corrupt = path_ + ": corrupt map (";
  if (nodes_read_ >= nodes_) throw Error(corrupt + "the node stream does not match its header)");
  {
    const ScopedNodeFormat node_format(format_);
    node->readData(*stream_);
  }
  char children = 0;
  stream_->read(&children, 1);
  if (!*stream_) throw Error(corrupt + "the node stream ends inside node " + std::to_string(nodes_read_) + ")");
  RequireFinite(*node, nodes_read_, path_);
  ++nodes_read_;
  const auto bits = static_cast<unsigned char>(children);
  if (bits != 0 && depth >= max_depth_) throw Error(corrupt + "a node lies deeper than the tree depth)");
  return bits;
}

void MapFileReader::Finish() {
  const bool at_end = stream_->peek() == std::char_traits<char>::eof();
  if (nodes_read_ != nodes_ || !at_end) {
    throw Error(path_ + ": corrupt map (the node stream does not match its header)");
  }
}

}  // namespace internal
}  // namespace ssta
