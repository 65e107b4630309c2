#include "ssta/eval/confusion_matrix.h"

#include <cmath>
#include <cstdio>
#include <limits>

#include "ssta/core/error.h"

namespace ssta {
namespace {

constexpr int kFirstVerdict = 1;
constexpr int kLastVerdict = 3;

double Ratio(std::int64_t numerator, std::int64_t denominator) {
  if (denominator == 0) return std::numeric_limits<double>::quiet_NaN();
  return static_cast<double>(numerator) / static_cast<double>(denominator);
}

int VerdictIndex(TravClass c) {
  const int i = static_cast<int>(c);
  SSTA_CHECK(i >= kFirstVerdict && i <= kLastVerdict, "IoU is defined for classes 1..3 only");
  return i;
}

std::string FormatRatio(double value) {
  if (std::isnan(value)) return "   n/a";
  char buffer[32];
  std::snprintf(buffer, sizeof buffer, "%6.4f", value);
  return buffer;
}

}  // namespace

void ConfusionMatrix::Add(std::uint8_t truth, std::uint8_t predicted, std::int64_t count) {
  SSTA_CHECK(count >= 0, "ConfusionMatrix::Add: negative count");
  SSTA_CHECK(predicted < kSize, "ConfusionMatrix::Add: predicted class must be 0..4");
  if (truth == kDontCare) {
    dont_care_ += count;
    return;
  }
  SSTA_CHECK(truth < kSize, "ConfusionMatrix::Add: truth class must be 0..4 or 255");
  counts_[truth][predicted] += count;
}

ConfusionMatrix& ConfusionMatrix::operator+=(const ConfusionMatrix& other) {
  for (int t = 0; t < kSize; ++t) {
    for (int p = 0; p < kSize; ++p) counts_[t][p] += other.counts_[t][p];
  }
  dont_care_ += other.dont_care_;
  return *this;
}

std::int64_t ConfusionMatrix::Count(int truth, int predicted) const {
  SSTA_CHECK(truth >= 0 && truth < kSize && predicted >= 0 && predicted < kSize,
             "ConfusionMatrix::Count: class out of range");
  return counts_[truth][predicted];
}

std::int64_t ConfusionMatrix::TruthTotal(int truth) const {
  SSTA_CHECK(truth >= 0 && truth < kSize, "ConfusionMatrix::TruthTotal: class out of range");
  std::int64_t sum = 0;
  for (int p = 0; p < kSize; ++p) sum += counts_[truth][p];
  return sum;
}

std::int64_t ConfusionMatrix::ScoredPredictedTotal(int predicted) const {
  SSTA_CHECK(predicted >= 0 && predicted < kSize, "ConfusionMatrix: class out of range");
  std::int64_t sum = 0;
  for (int t = kFirstVerdict; t <= kLastVerdict; ++t) sum += counts_[t][predicted];
  return sum;
}

std::int64_t ConfusionMatrix::Scored() const {
  std::int64_t sum = 0;
  for (int t = kFirstVerdict; t <= kLastVerdict; ++t) sum += TruthTotal(t);
  return sum;
}

std::int64_t ConfusionMatrix::Correct() const {
  std::int64_t sum = 0;
  for (int c = kFirstVerdict; c <= kLastVerdict; ++c) sum += counts_[c][c];
  return sum;
}

std::int64_t ConfusionMatrix::Decided() const {
  std::int64_t sum = 0;
  for (int p = kFirstVerdict; p <= kLastVerdict; ++p) sum += ScoredPredictedTotal(p);
  return sum;
}

std::int64_t ConfusionMatrix::IouDenominator(TravClass c) const {
  const int i = VerdictIndex(c);
  // TP + FN is the whole truth row; FP is the rest of the column over scored rows.
  return TruthTotal(i) + ScoredPredictedTotal(i) - counts_[i][i];
}

double ConfusionMatrix::Iou(TravClass c) const {
  const int i = VerdictIndex(c);
  return Ratio(counts_[i][i], IouDenominator(c));
}

int ConfusionMatrix::PresentClasses() const {
  int n = 0;
  for (int c = kFirstVerdict; c <= kLastVerdict; ++c) n += IsPresent(static_cast<TravClass>(c));
  return n;
}

double ConfusionMatrix::MeanIou() const {
  double sum = 0.0;
  int n = 0;
  for (int c = kFirstVerdict; c <= kLastVerdict; ++c) {
    const auto cls = static_cast<TravClass>(c);
    if (!IsPresent(cls)) continue;
    sum += Iou(cls);
    ++n;
  }
  return n == 0 ? std::numeric_limits<double>::quiet_NaN() : sum / n;
}

double ConfusionMatrix::Accuracy() const { return Ratio(Correct(), Scored()); }
double ConfusionMatrix::Coverage() const { return Ratio(Decided(), Scored()); }
double ConfusionMatrix::DecidedAccuracy() const { return Ratio(Correct(), Decided()); }

double ConfusionMatrix::Recall(TravClass c) const {
  const int i = VerdictIndex(c);
  return Ratio(counts_[i][i], TruthTotal(i));
}

namespace {
constexpr int kTrav = static_cast<int>(TravClass::kTraversable);
constexpr int kSemi = static_cast<int>(TravClass::kSemiTraversable);
constexpr int kNon = static_cast<int>(TravClass::kNonTraversable);
}  // namespace

bool ConfusionMatrix::IsUnsafe(std::uint8_t truth, std::uint8_t predicted) {
  return truth == kNon && (predicted == kTrav || predicted == kSemi);
}
bool ConfusionMatrix::IsFalselyBlocked(std::uint8_t truth, std::uint8_t predicted) {
  return (truth == kTrav || truth == kSemi) && predicted == kNon;
}
std::int64_t ConfusionMatrix::Unsafe() const { return counts_[kNon][kTrav] + counts_[kNon][kSemi]; }
double ConfusionMatrix::UnsafeRate() const { return Ratio(Unsafe(), TruthTotal(kNon)); }
std::int64_t ConfusionMatrix::FalselyBlocked() const { return counts_[kTrav][kNon] + counts_[kSemi][kNon]; }
double ConfusionMatrix::FalselyBlockedRate() const {
  return Ratio(FalselyBlocked(), TruthTotal(kTrav) + TruthTotal(kSemi));
}

std::string ConfusionMatrix::BriefReport(std::string_view unit) const {
  const std::string u(unit);
  char line[256];
  std::string out;
  std::snprintf(line, sizeof line,
                "scored %s: %lld (truth 1..3); not scored: don't care %lld, truth unknown %lld, "
                "truth undecided %lld\n",
                u.c_str(), static_cast<long long>(Scored()), static_cast<long long>(dont_care_),
                static_cast<long long>(TruthTotal(0)), static_cast<long long>(TruthTotal(4)));
  out += line;
  out += "accuracy " + FormatRatio(Accuracy()) + "   coverage " + FormatRatio(Coverage()) +
         "   decided accuracy " + FormatRatio(DecidedAccuracy()) + "   mean IoU " +
         FormatRatio(MeanIou()) + " (over " + std::to_string(PresentClasses()) +
         " present classes)\n";
  std::snprintf(line, sizeof line,
                "unsafe (truly non-traversable, answered traversable or semi): %lld of %lld (%s)\n"
                "falsely blocked (truly free, answered non-traversable): %lld of %lld (%s)\n",
                static_cast<long long>(Unsafe()), static_cast<long long>(TruthTotal(kNon)),
                FormatRatio(UnsafeRate()).c_str(), static_cast<long long>(FalselyBlocked()),
                static_cast<long long>(TruthTotal(kTrav) + TruthTotal(kSemi)),
                FormatRatio(FalselyBlockedRate()).c_str());
  out += line;
  out += "class                 IoU  recall    truth  predicted (on scored " + u + ")\n";
  for (int c = kFirstVerdict; c <= kLastVerdict; ++c) {
    const auto cls = static_cast<TravClass>(c);
    std::snprintf(line, sizeof line, "%-18s %s  %s %8lld %10lld\n",
                  std::string(ClassName(cls)).c_str(), FormatRatio(Iou(cls)).c_str(), FormatRatio(Recall(cls)).c_str(),
                  static_cast<long long>(TruthTotal(c)),
                  static_cast<long long>(ScoredPredictedTotal(c)));
    out += line;
  }
  out += "confusion (rows truth, columns predicted):\n";
  std::snprintf(line, sizeof line, "%-18s %10s %10s %10s %10s %10s\n", "truth \\ predicted",
                "unknown", "travers.", "semi", "non", "undecided");
  out += line;
  for (int t = 0; t < kSize; ++t) {
    std::snprintf(line, sizeof line, "%-18s", std::string(ClassName(static_cast<TravClass>(t))).c_str());
    out += line;
    for (int p = 0; p < kSize; ++p) {
      std::snprintf(line, sizeof line, " %10lld", static_cast<long long>(counts_[t][p]));
      out += line;
    }
    out += '\n';
  }
  return out;
}

}  // namespace ssta
