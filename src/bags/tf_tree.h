#pragma once

// Private: the transforms a bag's /tf and /tf_static carry, as a tree of frames that can be
// asked for the transform between two frames at a time.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace ssta::internal {

class TfTree {
 public:
  /// Adds parent_T_child at `stamp_ns`. A static transform replaces the link's earlier ones.
  void Add(const std::string& parent, const std::string& child, std::int64_t stamp_ns,
           const Eigen::Isometry3d& parent_T_child, bool is_static);

  /// True when `frame` is the parent or the child of a transform.
  bool Has(const std::string& frame) const;
  /// The top of `frame`'s chain of parents (`frame` itself when it has no parent).
  std::string RootOf(const std::string& frame) const;
  /// target_T_source at `t`, through the frames' common ancestor; nullopt when the two frames
  /// are not connected or a moving link on the way has no transform near `t` (moving links
  /// interpolate between their samples; outside their time range the nearest sample holds for
  /// kMaxExtrapolationNs; a link published once holds at all times, as a static one).
  std::optional<Eigen::Isometry3d> Lookup(const std::string& target, const std::string& source, std::int64_t t) const;
  /// The times at which a moving link between `frame` and its ancestor `ancestor` changes, sorted.
  std::vector<std::int64_t> ChangeTimes(const std::string& ancestor, const std::string& frame) const;

  static constexpr std::int64_t kMaxExtrapolationNs = 500'000'000;

 private:
  struct Link {
    std::string parent;
    bool is_static = false;
    std::vector<std::pair<std::int64_t, Eigen::Isometry3d>> samples;  ///< sorted by time
  };
  std::optional<Eigen::Isometry3d> ParentTChild(const Link& link, std::int64_t t) const;
  /// The frames from `frame` up to its root, `frame` first.
  std::vector<std::string> Chain(const std::string& frame) const;
  /// ancestor_T_frame at `t` along Chain(frame).
  std::optional<Eigen::Isometry3d> AncestorTFrame(const std::string& ancestor, const std::string& frame, std::int64_t t) const;

  std::map<std::string, Link> links_;  ///< by child frame
  std::map<std::string, int> parents_;  ///< frames that are some link's parent
};

}  // namespace ssta::internal
