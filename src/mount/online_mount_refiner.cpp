#include "ssta/mount/online_mount_refiner.h"

#include <iomanip>
#include <sstream>
#include <utility>

#include "mount/refinement_json.h"
#include "ssta/core/error.h"
#include "ssta/core/units.h"

namespace ssta {
namespace {


/// Index into OnlineRefinementSummary::rejected for a status other than kDetermined.
int RejectedIndex(RefinementStatus status) {
  switch (status) {
    case RefinementStatus::kTooFewFrames: return 0;
    case RefinementStatus::kNotBetterThanPrior: return 1;
    case RefinementStatus::kTerrainTooRough: return 2;
    default: return 3;
  }
}

constexpr RefinementStatus kRejectedStatuses[4] = {RefinementStatus::kTooFewFrames,
                                                   RefinementStatus::kNotBetterThanPrior,
                                                   RefinementStatus::kTerrainTooRough, RefinementStatus::kFailed};

double AngleDeg(const Eigen::Isometry3d& a, const Eigen::Isometry3d& b) {
  return RadToDeg(Eigen::AngleAxisd(a.linear().transpose() * b.linear()).angle());
}

}  // namespace

OnlineMountRefiner::OnlineMountRefiner(const RefinementOptions& options,
                                       const Eigen::Isometry3d& body_T_camera_configured,
                                       const Eigen::Isometry3d& body_T_camera_start)
    : options_(options), window_(options, body_T_camera_configured) {
  summary_.body_T_camera_configured = body_T_camera_configured;
  summary_.body_T_camera_start = body_T_camera_start;
  summary_.body_T_camera = body_T_camera_start;
}

bool OnlineMountRefiner::AddFrame(GroundEvidence evidence) {
  ++summary_.frames_offered;
  if (!summary_.last_applied) ++summary_.frames_before_first_applied;
  if (!evidence.usable) {
    summary_.no_evidence.push_back({evidence.timestamp_ns, evidence.reason});
    return false;
  }
  ++summary_.frames_with_evidence;
  const std::int64_t evidence_timestamp = evidence.timestamp_ns;
  window_.AddFrame(std::move(evidence));
  while (window_.NumFrames() > options_.window_frames) window_.DropOldest();
  ++since_solve_;
  const bool first = !last_result_;
  if (window_.NumFrames() < options_.min_frames) return false;
  if (!first && since_solve_ < options_.solve_every_frames) return false;

  since_solve_ = 0;
  last_result_ = window_.Solve();
  const MountRefinementResult& r = *last_result_;
  ++summary_.solves;
  summary_.solve_ms += r.solve_ms;
  summary_.history.push_back({summary_.frames_offered, evidence_timestamp, r.status, r.pitch_correction_deg,
                              r.roll_correction_deg, r.pitch_sigma_deg, r.roll_sigma_deg, r.frames_used});
  if (!r.applied()) {
    ++summary_.rejected[RejectedIndex(r.status)];
    summary_.last_rejection = RefinementStatusName(r.status) + ": " + r.message;
    return false;
  }
  ++summary_.applied;
  summary_.last_applied = r;
  summary_.last_applied->frames.clear();  // per-frame planes of one window: not needed later
  summary_.body_T_camera = r.body_T_camera_refined;
  return true;
}

std::string OnlineRefinementSummary::BriefReport() const {
  std::ostringstream r;
  r << std::fixed << std::setprecision(3);
  r << "online mount refinement: " << frames_with_evidence << " of " << frames_offered
    << " frames with ground evidence; " << solves << " solves, " << applied << " applied, " << rejected_total()
    << " rejected";
  if (rejected_total() > 0) {
    r << " (";
    bool comma = false;
    for (int i = 0; i < 4; ++i) {
      if (rejected[i] == 0) continue;
      r << (comma ? ", " : "") << rejected[i] << " " << RefinementStatusName(kRejectedStatuses[i]);
      comma = true;
    }
    r << ")";
  }
  r << "\n";
  if (last_applied) {
    const MountRefinementResult& a = *last_applied;
    r << "  cam0 mount in use: pitch correction " << a.pitch_correction_deg << " +- " << a.pitch_sigma_deg
      << " deg, roll correction " << a.roll_correction_deg << " +- " << a.roll_sigma_deg
      << " deg (1 sigma, against sensor.yaml; last applied solve over " << a.frames_used << " frames)\n";
    r << "  " << frames_before_first_applied << " frame(s) processed before the first applied solve";
    if (frames_reprocessed > 0) r << ", " << frames_reprocessed << " processed again with it before fusion";
    r << "\n";
  } else if (!body_T_camera.isApprox(body_T_camera_configured, 1e-12)) {
    r << "  cam0 mount in use: the one the map recorded, " << AngleDeg(body_T_camera_configured, body_T_camera)
      << " deg from sensor.yaml; no solve applied in this run\n";
  } else {
    r << "  cam0 mount in use: sensor.yaml's (no solve applied)\n";
  }
  if (solves == 0) r << "  no solve: fewer frames with ground evidence than min_frames\n";
  if (!last_rejection.empty()) r << "  last rejected: " << last_rejection << "\n";
  if (!no_evidence.empty()) {
    r << "  no ground evidence in " << no_evidence.size() << " frame(s), first " << no_evidence.front().timestamp_ns
      << ": " << no_evidence.front().reason << "\n";
  }
  r << "  solve time: " << solve_ms << " ms in total\n";
  return r.str();
}

std::string OnlineRefinementSummary::Json() const {
  internal::JsonWriter json;
  json.BeginObject();
  json.Key("frames_offered");
  json.Integer(frames_offered);
  json.Key("frames_with_evidence");
  json.Integer(frames_with_evidence);
  json.Key("solves");
  json.Integer(solves);
  json.Key("applied");
  json.Integer(applied);
  json.Key("rejected");
  json.BeginObject();
  for (int i = 0; i < 4; ++i) {
    json.Key(RefinementStatusName(kRejectedStatuses[i]));
    json.Integer(rejected[i]);
  }
  json.EndObject();
  json.Key("last_rejection");
  json.String(last_rejection);
  json.Key("frames_before_first_applied");
  json.Integer(frames_before_first_applied);
  json.Key("frames_reprocessed");
  json.Integer(frames_reprocessed);
  json.Key("solve_ms");
  json.Number(solve_ms);
  json.Key("angle_from_configured_deg");
  json.Number(AngleDeg(body_T_camera_configured, body_T_camera));
  json.Key("last_applied");
  if (last_applied) {
    internal::WriteRefinementJson(*last_applied, &json);
  } else {
    json.Null();
  }
  json.Key("body_T_camera_configured");
  json.MatrixRows(body_T_camera_configured.matrix());
  json.Key("body_T_camera_start");
  json.MatrixRows(body_T_camera_start.matrix());
  json.Key("body_T_camera");
  json.MatrixRows(body_T_camera.matrix());
  json.Key("history");
  json.BeginArray();
  for (const OnlineSolve& h : history) {
    json.BeginObject();
    json.Key("frame");
    json.Integer(h.frame);
    json.Key("timestamp_ns");
    json.Integer(h.timestamp_ns);
    json.Key("status");
    json.String(RefinementStatusName(h.status));
    json.Key("pitch_correction_deg");
    json.Number(h.pitch_correction_deg);
    json.Key("roll_correction_deg");
    json.Number(h.roll_correction_deg);
    json.Key("pitch_sigma_deg");
    json.Number(h.pitch_sigma_deg);
    json.Key("roll_sigma_deg");
    json.Number(h.roll_sigma_deg);
    json.Key("frames_used");
    json.Integer(h.frames_used);
    json.EndObject();
  }
  json.EndArray();
  json.Key("no_evidence");
  internal::WriteSkippedFramesJson(no_evidence, &json);
  json.EndObject();
  return json.Take();
}

}  // namespace ssta
