// MakeComparisonPicture: the only eval source that uses OpenCV (text and rectangles).

#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ssta/core/classes.h"
#include "ssta/eval/label_evaluator.h"

namespace ssta {
namespace {

constexpr int kTitleHeight = 18;   // [px] band above each panel
constexpr int kGap = 4;            // [px] between panels
constexpr int kLegendHeight = 22;  // [px] strip at the bottom
constexpr double kFontScale = 0.4;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

const cv::Scalar kBackground(224, 224, 224);
const cv::Scalar kText(0, 0, 0);
// Error panel colours (R, G, B: the canvas is built in RGB order).
const Rgb8 kRight{64, 64, 64};
const Rgb8 kWrong{255, 0, 255};
const Rgb8 kNoVerdict{255, 165, 0};
const Rgb8 kNotScored{255, 255, 255};

cv::Scalar ToScalar(const Rgb8& c) { return cv::Scalar(c.r, c.g, c.b); }

ImageRgb ErrorPanel(const ImageU8& truth, const ImageU8& predicted) {
  ImageRgb out(truth.width(), truth.height());
  for (std::size_t i = 0; i < truth.size(); ++i) {
    const std::uint8_t t = truth[i];
    const std::uint8_t p = predicted[i];
    if (t < 1 || t > 3) {
      out[i] = kNotScored;
    } else if (p < 1 || p > 3) {
      out[i] = kNoVerdict;
    } else {
      out[i] = p == t ? kRight : kWrong;
    }
  }
  return out;
}

void Paste(const ImageRgb& panel, int x0, int y0, cv::Mat* canvas) {
  for (int v = 0; v < panel.height(); ++v) {
    auto* dst = canvas->ptr<cv::Vec3b>(y0 + v) + x0;
    const Rgb8* src = panel.row(v);
    for (int u = 0; u < panel.width(); ++u) dst[u] = cv::Vec3b(src[u].r, src[u].g, src[u].b);
  }
}

struct LegendEntry {
  Rgb8 colour;
  std::string name;
};

std::vector<LegendEntry> LegendEntries() {
  return {{ClassColour(TravClass::kTraversable), "traversable"},
          {ClassColour(TravClass::kSemiTraversable), "semi"},
          {ClassColour(TravClass::kNonTraversable), "non"},
          {Rgb8{0, 0, 0}, "unknown"},
          {Rgb8{128, 128, 128}, "undecided"},
          {Rgb8{255, 255, 255}, "don't care"},
          {kRight, "right"},
          {kWrong, "wrong"},
          {kNoVerdict, "no verdict"},
          {kNotScored, "not scored"}};
}

int TextWidth(const std::string& text) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, kFontScale, 1, &baseline).width;
}

constexpr int kSwatch = 12;
constexpr int kFirstErrorEntry = 6;  // entries from here on explain the errors panel
constexpr int kGroupGap = 16;        // [px] extra space between the two legend groups

int LegendWidth() {
  int width = kGap + kGroupGap;
  for (const auto& entry : LegendEntries()) width += kSwatch + 4 + TextWidth(entry.name) + 10;
  return width;
}

void DrawLegend(int y0, cv::Mat* canvas) {
  int x = kGap;
  const int swatch_y = y0 + (kLegendHeight - kSwatch) / 2;
  const std::vector<LegendEntry> entries = LegendEntries();
  for (std::size_t i = 0; i < entries.size(); ++i) {
    const LegendEntry& entry = entries[i];
    if (i == kFirstErrorEntry) x += kGroupGap;
    cv::rectangle(*canvas, cv::Rect(x, swatch_y, kSwatch, kSwatch), ToScalar(entry.colour), cv::FILLED);
    cv::rectangle(*canvas, cv::Rect(x, swatch_y, kSwatch, kSwatch), kText, 1);
    x += kSwatch + 4;
    cv::putText(*canvas, entry.name, cv::Point(x, swatch_y + kSwatch - 2), kFont, kFontScale, kText, 1,
                cv::LINE_AA);
    x += TextWidth(entry.name) + 10;
  }
}

}  // namespace

ImageRgb MakeComparisonPicture(const ImageU8& truth, const ImageU8& predicted) {
  ScoreLabels(truth, predicted);  // validates sizes and ids (throws ssta::Error)
  const std::vector<std::pair<std::string, ImageRgb>> panels = {
      {"truth", ColourizeLabels(truth)},
      {"prediction", ColourizeLabels(predicted)},
      {"errors", ErrorPanel(truth, predicted)}};
  const int w = truth.width();
  const int h = truth.height();
  const int panels_width = 3 * w + 4 * kGap;
  const int width = std::max(panels_width, LegendWidth());
  const int height = kTitleHeight + h + kGap + kLegendHeight;
  cv::Mat canvas(height, width, CV_8UC3, kBackground);
  int x = kGap;
  for (const auto& [title, panel] : panels) {
    cv::putText(canvas, title, cv::Point(x, kTitleHeight - 5), kFont, kFontScale, kText, 1, cv::LINE_AA);
    Paste(panel, x, kTitleHeight, &canvas);
    x += w + kGap;
  }
  DrawLegend(kTitleHeight + h + kGap, &canvas);

  ImageRgb out(width, height);
  for (int v = 0; v < height; ++v) {
    const auto* src = canvas.ptr<cv::Vec3b>(v);
    Rgb8* dst = out.row(v);
    for (int u = 0; u < width; ++u) dst[u] = Rgb8{src[u][0], src[u][1], src[u][2]};
  }
  return out;
}

}  // namespace ssta
