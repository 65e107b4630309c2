#include "tf_tree.h"

#include <algorithm>
#include <set>

namespace ssta::internal {

void TfTree::Add(const std::string& parent, const std::string& child, std::int64_t stamp_ns,
                 const Eigen::Isometry3d& parent_T_child, bool is_static) {
  Link& link = links_[child];
  if (is_static || link.is_static != is_static || link.parent != parent) link.samples.clear();
  link.parent = parent;
  link.is_static = is_static;
  auto& s = link.samples;
  const auto at = std::upper_bound(s.begin(), s.end(), stamp_ns,
                                   [](std::int64_t t, const auto& sample) { return t < sample.first; });
  s.insert(at, {stamp_ns, parent_T_child});
  ++parents_[parent];
}

bool TfTree::Has(const std::string& frame) const { return links_.count(frame) > 0 || parents_.count(frame) > 0; }

std::vector<std::string> TfTree::Chain(const std::string& frame) const {
  std::vector<std::string> chain = {frame};
  std::set<std::string> seen = {frame};
  for (auto it = links_.find(frame); it != links_.end(); it = links_.find(it->second.parent)) {
    if (!seen.insert(it->second.parent).second) break;  // a loop in a broken tree: stop at it
    chain.push_back(it->second.parent);
  }
  return chain;
}

std::string TfTree::RootOf(const std::string& frame) const { return Chain(frame).back(); }

std::optional<Eigen::Isometry3d> TfTree::ParentTChild(const Link& link, std::int64_t t) const {
  const auto& s = link.samples;
  if (s.empty()) return std::nullopt;
  if (link.is_static || s.size() == 1) return s.front().second;
  if (t <= s.front().first) {
    if (s.front().first - t > kMaxExtrapolationNs) return std::nullopt;
    return s.front().second;
  }
  if (t >= s.back().first) {
    if (t - s.back().first > kMaxExtrapolationNs) return std::nullopt;
    return s.back().second;
  }
  const auto b = std::lower_bound(s.begin(), s.end(), t, [](const auto& sample, std::int64_t time) { return sample.first < time; });
  const auto a = b - 1;
  if (b->first == t) return b->second;
  const double f = static_cast<double>(t - a->first) / static_cast<double>(b->first - a->first);
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = Eigen::Quaterniond(a->second.linear()).slerp(f, Eigen::Quaterniond(b->second.linear())).toRotationMatrix();
  out.translation() = (1.0 - f) * a->second.translation() + f * b->second.translation();
  return out;
}

std::optional<Eigen::Isometry3d> TfTree::AncestorTFrame(const std::string& ancestor, const std::string& frame,
                                                        std::int64_t t) const {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  for (std::string f = frame; f != ancestor;) {
    const auto it = links_.find(f);
    if (it == links_.end()) return std::nullopt;
    const auto step = ParentTChild(it->second, t);
    if (!step) return std::nullopt;
    out = *step * out;
    f = it->second.parent;
    if (f == frame) return std::nullopt;  // a loop
  }
  return out;
}

std::optional<Eigen::Isometry3d> TfTree::Lookup(const std::string& target, const std::string& source, std::int64_t t) const {
  if (target == source) return Eigen::Isometry3d::Identity();
  const auto up_target = Chain(target);
  const auto up_source = Chain(source);
  const auto common = std::find_first_of(up_source.begin(), up_source.end(), up_target.begin(), up_target.end());
  if (common == up_source.end()) return std::nullopt;
  const auto ancestor_T_source = AncestorTFrame(*common, source, t);
  const auto ancestor_T_target = AncestorTFrame(*common, target, t);
  if (!ancestor_T_source || !ancestor_T_target) return std::nullopt;
  return ancestor_T_target->inverse() * *ancestor_T_source;
}

std::vector<std::int64_t> TfTree::ChangeTimes(const std::string& ancestor, const std::string& frame) const {
  std::vector<std::int64_t> times;
  for (std::string f = frame; f != ancestor;) {
    const auto it = links_.find(f);
    if (it == links_.end()) break;
    if (!it->second.is_static) {
      for (const auto& sample : it->second.samples) times.push_back(sample.first);
    }
    f = it->second.parent;
    if (f == frame) break;
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  return times;
}

}  // namespace ssta::internal
