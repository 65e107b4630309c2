#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <octomap/OcTree.h>

#include "map_test_util.h"
#include "ssta/files/file_util.h"
#include "temp_dir.h"

namespace ssta {
namespace {

using testing::OctoMapCarving;

using internal::TravNode;
using internal::TravOcTree;
using testing::Pt;
using testing::TempDir;
using testing::Tree;

/// A few frames over the floor-and-box world from different places, with noisy class verdicts
/// so that the voxels end up with varied payloads.
std::vector<std::vector<ClassifiedPoint>> Frames(int count) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<float> jitter(-0.04f, 0.04f);
  std::uniform_int_distribution<int> flip(0, 9);
  std::vector<std::vector<ClassifiedPoint>> frames;
  for (int f = 0; f < count; ++f) {
    std::vector<ClassifiedPoint> points = testing::FloorAndBox();
    for (ClassifiedPoint& p : points) {
      p.world_p += Eigen::Vector3f(jitter(rng), jitter(rng), jitter(rng));
      p.slope_deg += jitter(rng) * 100.0f;
      p.step_m += jitter(rng);
      const int r = flip(rng);
      if (r == 0) p.cls = TravClass::kSemiTraversable;
      if (r == 1) p.cls = TravClass::kUndecided;
    }
    // Something that moves away: a post present in the first frames only.
    if (f < 2) {
      for (int iz = 1; iz < 10; ++iz) points.push_back(Pt(2.55, 0.55, 0.05 + 0.1 * iz, TravClass::kNonTraversable));
    }
    frames.push_back(std::move(points));
  }
  return frames;
}

Eigen::Vector3d FrameOrigin(int f) { return {0.3 + 0.5 * f, 0.2 + 0.3 * f, 1.2 + 0.1 * f}; }

/// Every node of both trees, inner ones included, in traversal order: same keys, depths,
/// occupancy and payload.
void ExpectSameTrees(const TravOcTree& a, const TravOcTree& b) {
  ASSERT_EQ(a.size(), b.size());
  ASSERT_EQ(a.getResolution(), b.getResolution());
  auto ia = a.begin_tree(), ib = b.begin_tree();
  std::size_t nodes = 0, leaves = 0;
  for (; ia != a.end_tree() && ib != b.end_tree(); ++ia, ++ib, ++nodes) {
    ASSERT_EQ(ia.getKey(), ib.getKey()) << nodes;
    ASSERT_EQ(ia.getDepth(), ib.getDepth()) << nodes;
    ASSERT_EQ(ia.isLeaf(), ib.isLeaf()) << nodes;
    ASSERT_TRUE(*ia == *ib) << "node " << nodes << " at depth " << ia.getDepth();
    leaves += ia.isLeaf();
  }
  EXPECT_TRUE(ia == a.end_tree());
  EXPECT_TRUE(ib == b.end_tree());
  EXPECT_EQ(nodes, a.size());
  EXPECT_GT(leaves, 1000u);
}

MapMetadata SomeMetadata() {
  MapMetadata m;
  m.vehicle.max_slope_deg = 30.0;
  m.vehicle.semi_slope_deg = 12.5;
  m.vehicle.max_step_m = 0.25;
  m.calibration_summary = "cam0: fu 458.654, cu 367.215\nbaseline: 0.110 m\n# not a comment: \"quoted\" 'x'";
  m.sequences = {"MH_01_easy", "seq with spaces", "x: y"};
  return m;
}

TraversabilityMap BuildMap(int frames) {
  MapOptions options = OctoMapCarving();
  options.max_range_m = 12.0;
  options.class_hit_log_odds = 0.1 + 0.2;  // 0.30000000000000004: must come back exactly
  TraversabilityMap map(options, SomeMetadata());
  const auto all = Frames(frames);
  for (int f = 0; f < frames; ++f) map.InsertFrame(all[f], FrameOrigin(f), 1000 + f);
  return map;
}

std::string ReadBytes(const std::string& path) { return ReadTextFile(path); }

void WriteBytes(const std::string& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out << bytes;
}

/// Expects Load(path) to throw ssta::Error whose message names the file and contains `what`.
void ExpectLoadError(const std::string& path, const std::string& what) {
  try {
    TraversabilityMap::Load(path);
    ADD_FAILURE() << "Load(" << path << ") did not throw";
  } catch (const Error& e) {
    const std::string message = e.what();
    EXPECT_NE(message.find(path), std::string::npos) << message;
    EXPECT_NE(message.find(what), std::string::npos) << message;
  }
}

TEST(MapFile, SaveThenLoadKeepsEveryNodeAndTheMetadata) {
  const TempDir dir;
  const TraversabilityMap map = BuildMap(4);
  const std::string path = dir / "map.ot";
  map.Save(path);
  const TraversabilityMap loaded = TraversabilityMap::Load(path);
  ExpectSameTrees(Tree(map), Tree(loaded));

  const MapMetadata& m = loaded.metadata();
  EXPECT_EQ(m.vehicle.max_slope_deg, 30.0);
  EXPECT_EQ(m.vehicle.semi_slope_deg, 12.5);
  EXPECT_EQ(m.vehicle.max_step_m, 0.25);
  EXPECT_EQ(m.vehicle.semi_step_m, map.metadata().vehicle.semi_step_m);
  EXPECT_EQ(m.calibration_summary, SomeMetadata().calibration_summary);
  EXPECT_EQ(m.sequences, SomeMetadata().sequences);
  EXPECT_EQ(loaded.options().max_range_m, 12.0);
  EXPECT_EQ(loaded.options().resolution_m, 0.1);
  EXPECT_EQ(loaded.options().class_miss_log_odds, map.options().class_miss_log_odds);
  EXPECT_EQ(loaded.options().class_hit_log_odds, 0.1 + 0.2);
  EXPECT_EQ(loaded.frames_inserted(), 4u);
  EXPECT_EQ(loaded.last_timestamp_ns(), 1003);
  EXPECT_EQ(loaded.software_version(), map.software_version());
  EXPECT_EQ(loaded.options().free_space_ray_cell, 1);  // exact rays: not named in the file
  EXPECT_EQ(ReadBytes(path).find("free_space_ray_cell"), std::string::npos);
  EXPECT_LT(loaded.options().free_space_obstacle_shortening_per_m2, 0.0);  // off: not named either
  EXPECT_EQ(ReadBytes(path).find("free_space_obstacle_shortening_per_m2"), std::string::npos);
  EXPECT_FALSE(loaded.options().free_space_keeps_traversable);
  EXPECT_EQ(ReadBytes(path).find("free_space_keeps_traversable"), std::string::npos);
  // Numbers as the shortest text that reads back exactly (maps/README.md): 30, not 3e+01.
  const std::string bytes = ReadBytes(path);
  for (const char* text : {"max_slope_deg: 30\n", "semi_slope_deg: 12.5\n", "max_step_m: 0.25\n", "max_range_m: 12\n",
                           "resolution_m: 0.1\n", "class_hit_log_odds: 0.30000000000000004\n"}) {
    EXPECT_NE(bytes.find(text), std::string::npos) << text;
  }
  // Saving the loaded map again gives the same bytes.
  loaded.Save(dir / "again.ot");
  EXPECT_EQ(ReadBytes(dir / "again.ot"), ReadBytes(path));
  // No temporary files are left behind.
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(dir.path()), {}), 2);
}

// The writer hashes and forwards the file in blocks; the trailer must still count and hash
// every byte before it, and each node take its 52 payload bytes and its child mask.
TEST(MapFile, TheTrailerCountsAndHashesEveryByteBeforeIt) {
  const TempDir dir;
  const TraversabilityMap map = BuildMap(4);
  const std::string path = dir / "map.ot";
  map.Save(path);
  const std::string bytes = ReadBytes(path);
  ASSERT_GT(bytes.size(), 3u * 65536u);  // several of the writer's blocks
  const std::size_t trailer = bytes.rfind("\n# ssta-map-end bytes ");
  ASSERT_NE(trailer, std::string::npos);
  std::uint64_t hash = 14695981039346656037ull;  // FNV-1a, 64 bit
  for (std::size_t i = 0; i < trailer; ++i) {
    hash ^= static_cast<unsigned char>(bytes[i]);
    hash *= 1099511628211ull;
  }
  char expected[96];
  std::snprintf(expected, sizeof(expected), "\n# ssta-map-end bytes %zu fnv1a64 %016llx\n", trailer,
                static_cast<unsigned long long>(hash));
  EXPECT_EQ(bytes.substr(trailer), expected);
  const std::size_t data = bytes.find("\ndata\n");
  ASSERT_NE(data, std::string::npos);
  EXPECT_EQ(trailer - (data + 6), Tree(map).size() * 53u);
}

TEST(MapFile, RefinedMountRoundTripsExactlyAndIsOptional) {
  const TempDir dir;
  TraversabilityMap map = BuildMap(2);
  map.Save(dir / "plain.ot");
  EXPECT_FALSE(TraversabilityMap::Load(dir / "plain.ot").metadata().refined_mount);

  RefinedMount mount;
  mount.configured.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  mount.configured.translation() = Eigen::Vector3d(0.2, 0.06, 0.6);
  mount.refined = Eigen::AngleAxisd(-0.05, Eigen::Vector3d::UnitY()) * mount.configured;
  MapMetadata metadata = map.metadata();
  metadata.refined_mount = mount;
  map.set_metadata(metadata);
  map.Save(dir / "refined.ot");
  const std::optional<RefinedMount> loaded = TraversabilityMap::Load(dir / "refined.ot").metadata().refined_mount;
  ASSERT_TRUE(loaded);
  EXPECT_EQ(loaded->configured.matrix(), mount.configured.matrix());  // shortest exact decimals
  EXPECT_EQ(loaded->refined.matrix(), mount.refined.matrix());

  // A mount that is no rigid transform (a scaled rotation) is refused on loading, by key.
  mount.refined.linear() *= 1.01;
  metadata.refined_mount = mount;
  map.set_metadata(metadata);
  map.Save(dir / "scaled.ot");
  try {
    TraversabilityMap::Load(dir / "scaled.ot");
    ADD_FAILURE() << "a scaled mount loaded";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("refined_body_T_cam0: not a rigid transform: rotation part"), std::string::npos)
        << e.what();
  }
}

TEST(MapFile, IsAnOctoMapFileThatOctoMapsFactoryReads) {
  const TempDir dir;
  const TraversabilityMap map = BuildMap(2);
  map.Save(dir / "map.ot");
  std::unique_ptr<octomap::AbstractOcTree> tree(octomap::AbstractOcTree::read(dir / "map.ot"));
  ASSERT_NE(tree, nullptr);
  EXPECT_EQ(tree->getTreeType(), "SstaTravOcTree");
  auto* trav = dynamic_cast<TravOcTree*>(tree.get());
  ASSERT_NE(trav, nullptr);
  ExpectSameTrees(Tree(map), *trav);
}

TEST(MapFile, EmptyMapRoundTrips) {
  const TempDir dir;
  const TraversabilityMap map(OctoMapCarving());
  map.Save(dir / "empty.ot");
  const TraversabilityMap loaded = TraversabilityMap::Load(dir / "empty.ot");
  EXPECT_EQ(loaded.NumNodes(), 0u);
  EXPECT_FALSE(loaded.TopSurfaceAt(0, 0).observed);
}

TEST(MapFile, MissingTruncatedOrDamagedFilesAreErrorsNamingTheFile) {
  const TempDir dir;
  ExpectLoadError(dir / "missing.ot", "not found");
  const TraversabilityMap map = BuildMap(2);
  const std::string good = dir / "good.ot";
  map.Save(good);
  const std::string bytes = ReadBytes(good);
  const std::string bad = dir / "bad.ot";
  for (const double keep : {0.0, 0.01, 0.05, 0.5, 0.99}) {
    WriteBytes(bad, bytes.substr(0, static_cast<std::size_t>(keep * bytes.size())));
    EXPECT_THROW(TraversabilityMap::Load(bad), Error) << keep;
  }
  WriteBytes(bad, bytes.substr(0, bytes.size() / 2));
  ExpectLoadError(bad, "truncated");
  WriteBytes(bad, bytes.substr(0, bytes.size() - 1));
  ExpectLoadError(bad, "truncated");
  std::string flipped = bytes;
  flipped[bytes.size() / 2] = static_cast<char>(flipped[bytes.size() / 2] ^ 0x5a);
  WriteBytes(bad, flipped);
  ExpectLoadError(bad, "checksum");
  WriteBytes(bad, "hello\n");
  ExpectLoadError(bad, "not an OctoMap");
}

/// `header` (up to and including "data\n", its "size" line set to `nodes`) + `stream`, with
/// a valid end marker: what a hand-made or bit-rotted-then-rehashed file could hold.
std::string Sealed(const std::string& header, std::uint64_t nodes, const std::string& stream) {
  std::string head = header;
  const auto size_at = head.find("\nsize ");
  head.replace(size_at + 1, head.find('\n', size_at + 1) - size_at - 1, "size " + std::to_string(nodes));
  const std::string body = head + stream;
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : body) {
    hash ^= static_cast<unsigned char>(c);
    hash *= 1099511628211ull;
  }
  char trailer[96];
  std::snprintf(trailer, sizeof(trailer), "\n# ssta-map-end bytes %zu fnv1a64 %016llx\n", body.size(),
                static_cast<unsigned long long>(hash));
  return body + trailer;
}

/// One node as TravNode::writeData writes it (40 bytes, `value` first), then its child bits.
std::string Node(float value, unsigned char children) {
  std::string out(52, '\0');
  std::memcpy(out.data(), &value, sizeof(value));
  return out + static_cast<char>(children);
}

TEST(MapFile, ANodeStreamThatLiesBehindAValidChecksumIsRejected) {
  // OctoMap's reader recurses once per level and trusts the stream: a chain of 300000 nodes,
  // each with one child, used to overflow the stack (a crash, not an error), a missing child
  // made it read past the end, and NaN payloads went into the map.
  const TempDir dir;
  const std::string good = dir / "good.ot";
  BuildMap(1).Save(good);
  const std::string bytes = ReadBytes(good);
  const std::string header = bytes.substr(0, bytes.find("\ndata\n") + 6);
  const std::string bad = dir / "bad.ot";

  std::string chain;
  const int deep = 300000;
  for (int i = 0; i < deep; ++i) chain += Node(0.0f, i + 1 < deep ? 0x01 : 0x00);
  WriteBytes(bad, Sealed(header, deep, chain));
  ExpectLoadError(bad, "deeper than the tree depth");

  WriteBytes(bad, Sealed(header, 3, Node(0.0f, 0x03) + Node(0.0f, 0x00)));  // the second child is missing
  ExpectLoadError(bad, "ends inside node 2");

  WriteBytes(bad, Sealed(header, 1, Node(std::nanf(""), 0x00)));
  ExpectLoadError(bad, "NaN or infinity");

  WriteBytes(bad, Sealed(header, 1, Node(0.0f, 0x00) + "extra"));
  ExpectLoadError(bad, "does not match its header");

  WriteBytes(bad, Sealed(header, 2, Node(0.0f, 0x00)));  // the header counts a node too many
  ExpectLoadError(bad, "does not match its header");

  // The same sealing around the real stream loads: the test's file surgery is sound.
  const std::string stream = bytes.substr(header.size(), bytes.rfind("\n# ssta-map-end") - header.size());
  WriteBytes(bad, Sealed(header, BuildMap(1).NumNodes(), stream));
  EXPECT_EQ(TraversabilityMap::Load(bad).NumNodes(), BuildMap(1).NumNodes());
}

/// The node stream of `stream` (format 2: 52 payload bytes and a child byte per node, depth
/// first) with each node's payload cut to format 1's 40 bytes.
std::string AsFormat1(const std::string& stream) {
  std::string out;
  std::size_t at = 0;
  std::vector<int> children_left;
  do {
    out += stream.substr(at, 40);
    const auto bits = static_cast<unsigned char>(stream[at + 52]);
    out += static_cast<char>(bits);
    at += 53;
    int count = 0;
    for (int i = 0; i < 8; ++i) count += (bits >> i) & 1;
    if (count > 0) children_left.push_back(count);
    while (!children_left.empty() && children_left.back() == 0) children_left.pop_back();
    if (!children_left.empty()) --children_left.back();
  } while (at < stream.size());
  return out;
}

TEST(MapFile, AFormatOneMapLoadsWithoutFusedHeights) {
  const TempDir dir;
  const std::string good = dir / "good.ot";
  const TraversabilityMap map = BuildMap(2);
  map.Save(good);
  const std::string bytes = ReadBytes(good);
  std::string header = bytes.substr(0, bytes.find("\ndata\n") + 6);
  header.replace(header.find("format_version: 2"), 17, "format_version: 1");
  const std::string stream = bytes.substr(header.size(), bytes.rfind("\n# ssta-map-end") - header.size());
  const std::string old = dir / "old.ot";
  WriteBytes(old, Sealed(header, map.NumNodes(), AsFormat1(stream)));
  const TraversabilityMap loaded = TraversabilityMap::Load(old);
  EXPECT_EQ(loaded.NumNodes(), map.NumNodes());
  const CellInfo cell = loaded.TopSurfaceAt(1.05, 1.05);
  EXPECT_EQ(cell.cls, map.TopSurfaceAt(1.05, 1.05).cls);
  EXPECT_NEAR(cell.surface_z_m, cell.center.z(), 1e-9);  // no fused height: the voxel's centre
}

TEST(MapFile, TheSensorPathKeepsAnOriginPerResolutionMovedAndSurvivesSaveAndLoad) {
  TraversabilityMap map(OctoMapCarving(), SomeMetadata());
  const auto frames = Frames(1);
  // Origins 0.5 m apart, then one 0.04 m from the last (less than a resolution: not kept).
  map.InsertFrame(frames[0], {0.3, 0.2, 1.2}, 1);
  map.InsertFrame(frames[0], {0.8, 0.2, 1.2}, 2);
  map.InsertFrame(frames[0], {0.84, 0.2, 1.2}, 3);
  map.InsertFrame(frames[0], {0.8, 0.7123456, 1.3}, 4);
  ASSERT_EQ(map.sensor_path().size(), 3u);
  EXPECT_TRUE(map.sensor_path()[1].isApprox(Eigen::Vector3d(0.8, 0.2, 1.2)));

  const TempDir dir;
  const std::string path = dir / "map.ot";
  map.Save(path);
  const TraversabilityMap loaded = TraversabilityMap::Load(path);
  ASSERT_EQ(loaded.sensor_path().size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) {
    EXPECT_LT((loaded.sensor_path()[i] - map.sensor_path()[i]).norm(), 1e-3) << i;  // to the millimetre
  }
  EXPECT_TRUE(BuildMap(0).sensor_path().empty());

  // A broken path is an error naming the key; a file without one reads as an empty path.
  const std::string bytes = ReadBytes(path);
  std::string header = bytes.substr(0, bytes.find("\ndata\n") + 6);
  const std::string stream = bytes.substr(header.size(), bytes.rfind("\n# ssta-map-end") - header.size());
  const std::size_t at = header.find("sensor_path: [");
  ASSERT_NE(at, std::string::npos);
  std::string odd = header;
  odd.insert(at + 14, "1, ");
  const std::string bad = dir / "bad.ot";
  WriteBytes(bad, Sealed(odd, map.NumNodes(), stream));
  ExpectLoadError(bad, "sensor_path: needs x, y, z triples");
  std::string none = header;
  none.erase(at - 7, none.find('\n', at) - (at - 7) + 1);  // the line "#@ssta sensor_path: [...]"
  ASSERT_EQ(none.find("sensor_path"), std::string::npos);
  const std::string old = dir / "old.ot";
  WriteBytes(old, Sealed(none, map.NumNodes(), stream));
  const TraversabilityMap without = TraversabilityMap::Load(old);
  EXPECT_TRUE(without.sensor_path().empty());
  EXPECT_EQ(without.NumNodes(), map.NumNodes());
}

TEST(MapFile, APlainOcTreeFileIsTheWrongTreeType) {
  const TempDir dir;
  octomap::OcTree plain(0.1);
  plain.updateNode(octomap::point3d(1.0f, 2.0f, 0.5f), true);
  const std::string path = dir / "plain.ot";
  ASSERT_TRUE(plain.write(path));
  ExpectLoadError(path, "tree type 'OcTree'");
}

TEST(MapFile, ANewerFormatVersionIsAnError) {
  const TempDir dir;
  const std::string path = dir / "map.ot";
  BuildMap(1).Save(path);
  std::string bytes = ReadBytes(path);
  const std::string tag = "#@ssta format_version: 2\n";
  const std::size_t at = bytes.find(tag);
  ASSERT_NE(at, std::string::npos);
  bytes.replace(at, tag.size(), "#@ssta format_version: 3\n");
  WriteBytes(path, bytes);
  ExpectLoadError(path, "newer");
}

TEST(MapFile, ResumingEqualsOnePass) {
  const auto frames = Frames(6);
  MapOptions options = OctoMapCarving();
  options.max_range_m = 12.0;
  TraversabilityMap one_pass(options, SomeMetadata());
  for (int f = 0; f < 6; ++f) one_pass.InsertFrame(frames[f], FrameOrigin(f), 1000 + f);

  const TempDir dir;
  {
    TraversabilityMap first(options, SomeMetadata());
    for (int f = 0; f < 3; ++f) first.InsertFrame(frames[f], FrameOrigin(f), 1000 + f);
    first.Save(dir / "part.ot");
  }
  TraversabilityMap resumed = TraversabilityMap::Load(dir / "part.ot");
  for (int f = 3; f < 6; ++f) resumed.InsertFrame(frames[f], FrameOrigin(f), 1000 + f);

  ExpectSameTrees(Tree(one_pass), Tree(resumed));
  EXPECT_EQ(resumed.frames_inserted(), 6u);
  one_pass.Save(dir / "one.ot");
  resumed.Save(dir / "resumed.ot");
  EXPECT_EQ(ReadBytes(dir / "one.ot"), ReadBytes(dir / "resumed.ot"));
}

TEST(MapFile, SaveIntoAMissingFolderNamesTheFile) {
  const TempDir dir;
  const std::string path = dir / "no/such/dir/map.ot";
  try {
    TraversabilityMap(OctoMapCarving()).Save(path);
    ADD_FAILURE() << "no error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find(path), std::string::npos) << e.what();
  }
}


TEST(MapFile, OptionsOnlyNamedWhenSetTravelWithTheMapFile) {
  // free_space_ray_cell, free_space_obstacle_shortening_per_m2 and free_space_keeps_traversable
  // are written only when they are not their defaults (test above); set, they must come back.
  const TempDir dir;
  MapOptions options = OctoMapCarving();
  options.free_space_ray_cell = 4;
  options.free_space_obstacle_shortening_per_m2 = 0.008;
  options.free_space_keeps_traversable = true;
  TraversabilityMap map(options);
  map.InsertFrame(testing::FloorAndBox(), testing::FloorAndBoxOrigin(), 1);
  map.Save(dir / "set.ot");
  const TraversabilityMap loaded = TraversabilityMap::Load(dir / "set.ot");
  EXPECT_EQ(loaded.options().free_space_ray_cell, 4);
  EXPECT_EQ(loaded.options().free_space_obstacle_shortening_per_m2, 0.008);
  EXPECT_TRUE(loaded.options().free_space_keeps_traversable);
  ExpectSameTrees(Tree(map), Tree(loaded));
}

}  // namespace
}  // namespace ssta
