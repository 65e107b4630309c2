// RenderMapPicture and RenderMapDiffPicture: the exported grid and a diff drawn for people, with
// text, through OpenCV's imgproc.

#include "ssta/pictures/map_picture.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "ssta/core/error.h"
#include "ssta/io/image_io.h"
#include "ssta/pictures/map_diff_picture.h"

namespace ssta {
namespace {

namespace colours = picture_colours;

constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kFontScale = 0.45;
constexpr int kMargin = 12;        // [px] around everything
constexpr int kAxisLeft = 56;      // [px] left of the map: tick labels of y
constexpr int kAxisBottom = 40;    // [px] below the map: tick labels of x
constexpr int kTitleHeight = 66;   // [px] two lines of title and the y axis' name above the map
constexpr int kLegendWidth = 190;  // [px] right of the map
constexpr int kSwatch = 14;
constexpr int kLegendRow = 22;
constexpr int kMinTickSpacingPx = 70;
const cv::Scalar kInk(40, 40, 40);

cv::Scalar ToScalar(const Rgb8& c) { return cv::Scalar(c.r, c.g, c.b); }  // the canvas is RGB

Rgb8 ClassRgb(std::uint8_t cls) {
  switch (static_cast<TravClass>(cls)) {
    case TravClass::kTraversable: return colours::kTraversable;
    case TravClass::kSemiTraversable: return colours::kSemiTraversable;
    case TravClass::kNonTraversable: return colours::kNonTraversable;
    case TravClass::kUndecided: return colours::kUndecided;
    default: return colours::kUnknown;
  }
}

/// Lambertian shade in [0, 1] of a surface with gradient (dz/dx, dz/dy), lit from the picture's
/// upper left (from -x, +y) at 45 deg elevation, the cartographers' convention.
float Shade(float dzdx, float dzdy) {
  const Eigen::Vector3f normal = Eigen::Vector3f(-dzdx, -dzdy, 1.0f).normalized();
  const Eigen::Vector3f light = Eigen::Vector3f(-1.0f, 1.0f, std::sqrt(2.0f)).normalized();
  return std::max(0.0f, normal.dot(light));
}

/// Per-cell brightness factor from the heights (1 on level ground; flat 1 where a neighbour is
/// missing on both sides of an axis).
ImageF HillshadeFactors(const GridProjection& grid) {
  const int w = grid.width();
  const int h = grid.height();
  const float res = static_cast<float>(grid.resolution_m);
  const float level = Shade(0.0f, 0.0f);
  ImageF factor(w, h, 1.0f);
  auto height_at = [&](int v, int u) {
    return (u < 0 || v < 0 || u >= w || v >= h) ? std::nanf("") : grid.height_m(v, u);
  };
  // One central (or one-sided) difference along an axis; 0 when neither side is known.
  auto slope = [&](float z, float minus, float plus) {
    if (std::isfinite(minus) && std::isfinite(plus)) return (plus - minus) / (2.0f * res);
    if (std::isfinite(plus)) return (plus - z) / res;
    if (std::isfinite(minus)) return (z - minus) / res;
    return 0.0f;
  };
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const float z = grid.height_m(v, u);
      if (!std::isfinite(z)) continue;
      const float dzdx = slope(z, height_at(v, u - 1), height_at(v, u + 1));
      const float dzdy = slope(z, height_at(v + 1, u), height_at(v - 1, u));  // row 0 is the largest y
      // Relative to level ground, so level cells keep their class colour exactly.
      factor(v, u) = std::clamp(0.55f + 0.45f * Shade(dzdx, dzdy) / level, 0.55f, 1.2f);
    }
  }
  return factor;
}

std::uint8_t Scale(std::uint8_t channel, float factor) {
  return static_cast<std::uint8_t>(std::clamp(std::lround(channel * factor), 0L, 255L));
}

/// 1, 2 or 5 times a power of ten, the smallest at least `at_least`.
double NiceStep(double at_least) {
  const double power = std::pow(10.0, std::floor(std::log10(at_least)));
  for (const double m : {1.0, 2.0, 5.0, 10.0}) {
    if (m * power >= at_least - 1e-12) return m * power;
  }
  return 10.0 * power;
}

std::string Metres(double value, double step) {
  char buffer[32];
  std::snprintf(buffer, sizeof(buffer), step < 1.0 ? "%.1f" : "%.0f", std::abs(value) < 1e-9 ? 0.0 : value);
  return buffer;
}

int TextWidth(const std::string& text, double scale = kFontScale) {
  int baseline = 0;
  return cv::getTextSize(text, kFont, scale, 1, &baseline).width;
}

void Text(cv::Mat* canvas, const std::string& text, int x, int y, double scale = kFontScale) {
  cv::putText(*canvas, text, cv::Point(x, y), kFont, scale, kInk, 1, cv::LINE_AA);
}

void DrawCells(const GridProjection& grid, bool hillshade, int cell_px, const Eigen::Vector2i& top_left,
               cv::Mat* canvas) {
  const ImageF factor = hillshade ? HillshadeFactors(grid) : ImageF(grid.width(), grid.height(), 1.0f);
  for (int v = 0; v < grid.height(); ++v) {
    for (int u = 0; u < grid.width(); ++u) {
      const std::uint8_t cls = grid.classes(v, u);
      const bool known = cls >= 1 && cls <= 4;
      const Rgb8 base = ClassRgb(cls);
      const Rgb8 c = known ? Rgb8{Scale(base.r, factor(v, u)), Scale(base.g, factor(v, u)), Scale(base.b, factor(v, u))}
                           : base;
      for (int dv = 0; dv < cell_px; ++dv) {
        const int y = top_left.y() + v * cell_px + dv;
        auto* row = canvas->ptr<cv::Vec3b>(y);
        for (int du = 0; du < cell_px; ++du) {
          const int x = top_left.x() + u * cell_px + du;
          // Unknown: diagonal hatching every 6 px, so it differs from the white background.
          const Rgb8 px = !known && (x + y) % 6 == 0 ? colours::kUnknownHatch : c;
          row[x] = cv::Vec3b(px.r, px.g, px.b);
        }
      }
    }
  }
}

void DrawAxes(const MapPicture& picture, cv::Mat* canvas) {
  const GridProjection& grid = picture.grid;
  const int map_w = grid.width() * picture.cell_px;
  const int map_h = grid.height() * picture.cell_px;
  const Eigen::Vector2i tl = picture.map_top_left_px;
  cv::rectangle(*canvas, cv::Rect(tl.x() - 1, tl.y() - 1, map_w + 2, map_h + 2), kInk, 1);
  const double step = NiceStep(kMinTickSpacingPx * grid.resolution_m / picture.cell_px);
  const double x0 = grid.origin.x();
  const double y0 = grid.origin.y();
  const double x1 = x0 + grid.width() * grid.resolution_m;
  const double y1 = y0 + grid.height() * grid.resolution_m;
  for (double x = std::ceil(x0 / step - 1e-9) * step; x <= x1 + 1e-9; x += step) {
    const int u = picture.PixelOf({x, y0}).x();
    cv::line(*canvas, {u, tl.y() + map_h}, {u, tl.y() + map_h + 5}, kInk, 1);
    const std::string label = Metres(x, step);
    Text(canvas, label, u - TextWidth(label) / 2, tl.y() + map_h + 20);
  }
  for (double y = std::ceil(y0 / step - 1e-9) * step; y <= y1 + 1e-9; y += step) {
    const int v = picture.PixelOf({x0, y}).y();
    cv::line(*canvas, {tl.x() - 6, v}, {tl.x() - 1, v}, kInk, 1);
    const std::string label = Metres(y, step);
    Text(canvas, label, tl.x() - 10 - TextWidth(label), v + 5);
  }
  Text(canvas, "x [m]", tl.x() + map_w - TextWidth("x [m]"), tl.y() + map_h + 36);
  Text(canvas, "y [m]", kMargin, tl.y() - 8);
}

/// The path's start: a dark ring with a light centre at `centre`.
void DrawStartMarker(const cv::Point& centre, cv::Mat* canvas) {
  cv::circle(*canvas, centre, 7, ToScalar(colours::kPath), cv::FILLED, cv::LINE_AA);
  cv::circle(*canvas, centre, 4, ToScalar(colours::kPathHalo), cv::FILLED, cv::LINE_AA);
}

/// The path's end: a dark square with a light halo at `centre`.
void DrawEndMarker(const cv::Point& centre, cv::Mat* canvas) {
  cv::rectangle(*canvas, cv::Rect(centre.x - 5, centre.y - 5, 11, 11), ToScalar(colours::kPathHalo), cv::FILLED);
  cv::rectangle(*canvas, cv::Rect(centre.x - 4, centre.y - 4, 9, 9), ToScalar(colours::kPath), cv::FILLED);
}

void DrawPath(const MapPicture& picture, const std::vector<Eigen::Vector3d>& path, cv::Mat* canvas) {
  if (path.empty()) return;
  std::vector<cv::Point> points;
  for (const Eigen::Vector3d& p : path) {
    const Eigen::Vector2i px = picture.PixelOf(p.head<2>());
    points.emplace_back(px.x(), px.y());
  }
  // A white halo under the dark line keeps it visible on every class colour.
  cv::polylines(*canvas, points, false, ToScalar(colours::kPathHalo), 5, cv::LINE_AA);
  cv::polylines(*canvas, points, false, ToScalar(colours::kPath), 2, cv::LINE_AA);
  DrawEndMarker(points.back(), canvas);
  DrawStartMarker(points.front(), canvas);
}

/// A scale bar of a round length near a fifth of the map's width (at most the legend's width),
/// its top-left corner 12 px below (x, y), its length written under it.
void DrawScaleBar(const MapPicture& picture, int x, int y, cv::Mat* canvas) {
  const double px_per_m = picture.cell_px / picture.grid.resolution_m;
  const double width_m = picture.grid.width() * picture.grid.resolution_m;
  double length_m = NiceStep(std::max(width_m / 5.0, picture.grid.resolution_m));
  while (length_m * px_per_m > kLegendWidth - 30 && length_m > picture.grid.resolution_m) length_m /= 2.0;
  const int bar_px = std::max(1, static_cast<int>(std::lround(length_m * px_per_m)));
  y += 12;
  cv::rectangle(*canvas, cv::Rect(x, y, bar_px, 6), kInk, cv::FILLED);
  cv::rectangle(*canvas, cv::Rect(x + bar_px / 2, y + 1, bar_px - bar_px / 2 - 1, 4), cv::Scalar(255, 255, 255),
                cv::FILLED);
  char label[32];
  std::snprintf(label, sizeof(label), length_m < 1.0 ? "%.1f m" : "%.0f m", length_m);
  Text(canvas, label, x, y + 24);
}

void DrawLegend(const MapPicture& picture, bool hillshade, bool has_path, cv::Mat* canvas) {
  const int x = picture.map_top_left_px.x() + picture.grid.width() * picture.cell_px + 24;
  int y = picture.map_top_left_px.y();
  auto swatch = [&](const Rgb8& colour, bool hatched, const std::string& name) {
    cv::rectangle(*canvas, cv::Rect(x, y, kSwatch, kSwatch), ToScalar(colour), cv::FILLED);
    if (hatched) cv::line(*canvas, {x, y + kSwatch - 1}, {x + kSwatch - 1, y}, ToScalar(colours::kUnknownHatch), 1);
    cv::rectangle(*canvas, cv::Rect(x, y, kSwatch, kSwatch), kInk, 1);
    Text(canvas, name, x + kSwatch + 8, y + kSwatch - 2);
    y += kLegendRow;
  };
  swatch(colours::kTraversable, false, "traversable");
  swatch(colours::kSemiTraversable, false, "semi-traversable");
  swatch(colours::kNonTraversable, false, "non-traversable");
  swatch(colours::kUndecided, false, "undecided");
  swatch(colours::kUnknown, true, "unknown");
  if (has_path) {
    y += 4;
    cv::line(*canvas, {x, y + kSwatch / 2}, {x + kSwatch + 4, y + kSwatch / 2}, ToScalar(colours::kPath), 2, cv::LINE_AA);
    Text(canvas, "sensor path", x + kSwatch + 8, y + kSwatch - 2);
    y += kLegendRow;
    DrawStartMarker({x + kSwatch / 2, y + kSwatch / 2}, canvas);
    Text(canvas, "start", x + kSwatch + 8, y + kSwatch - 2);
    y += kLegendRow;
    DrawEndMarker({x + kSwatch / 2, y + kSwatch / 2}, canvas);
    Text(canvas, "end", x + kSwatch + 8, y + kSwatch - 2);
    y += kLegendRow;
  }
  if (hillshade) {
    y += 4;
    Text(canvas, "shaded by relief", x, y + kSwatch - 2, 0.4);
    y += kLegendRow;
  }

  DrawScaleBar(picture, x, y, canvas);
}

ImageRgb ToImage(const cv::Mat& canvas) {
  ImageRgb out(canvas.cols, canvas.rows);
  for (int v = 0; v < canvas.rows; ++v) {
    const auto* src = canvas.ptr<cv::Vec3b>(v);
    Rgb8* dst = out.row(v);
    for (int u = 0; u < canvas.cols; ++u) dst[u] = Rgb8{src[u][0], src[u][1], src[u][2]};
  }
  return out;
}

}  // namespace

Eigen::Vector2i MapPicture::PixelOf(const Eigen::Vector2d& xy_world) const {
  const double px_per_m = cell_px / grid.resolution_m;
  const double u = map_top_left_px.x() + (xy_world.x() - grid.origin.x()) * px_per_m;
  const double top_y = grid.origin.y() + grid.height() * grid.resolution_m;
  const double v = map_top_left_px.y() + (top_y - xy_world.y()) * px_per_m;
  return {static_cast<int>(std::floor(u)), static_cast<int>(std::floor(v))};
}

MapPicture RenderMapPicture(const TraversabilityMap& map, const MapPictureOptions& options) {
  if (options.max_cells < 100 || options.max_cells > 20000) {
    throw Error("picture max_cells: must be in 100..20000 (got " + std::to_string(options.max_cells) + ")");
  }
  if (options.max_map_px < 100 || options.max_map_px > 20000) {
    throw Error("picture max_map_px: must be in 100..20000 (got " + std::to_string(options.max_map_px) + ")");
  }
  GridExportOptions grid_options = options.grid;
  if (grid_options.region.isEmpty()) {
    // The observed surface and the whole path, with a metre around the path.
    const Eigen::AlignedBox3d bounds = map.SurfaceBounds();
    if (!bounds.isEmpty()) grid_options.region = Eigen::AlignedBox2d(bounds.min().head<2>(), bounds.max().head<2>());
    for (const Eigen::Vector3d& p : map.sensor_path()) {
      grid_options.region.extend(p.head<2>() - Eigen::Vector2d::Ones());
      grid_options.region.extend(p.head<2>() + Eigen::Vector2d::Ones());
    }
  }
  if (!(grid_options.resolution_m > 0.0) && !grid_options.region.isEmpty()) {
    // A large map is coarsened to max_cells along its longer side (the worst class per cell).
    const double res = map.options().resolution_m;
    const double longer = grid_options.region.sizes().maxCoeff();
    grid_options.resolution_m = res * std::max(1.0, std::ceil(longer / res / options.max_cells));
  }

  MapPicture picture;
  picture.grid = ProjectAsExported(map, grid_options);
  const int w = picture.grid.width();
  const int h = picture.grid.height();
  picture.cell_px = std::max(1, options.max_map_px / std::max(w, h));
  picture.map_top_left_px = Eigen::Vector2i(kMargin + kAxisLeft, kMargin + kTitleHeight);

  const bool has_path = !map.sensor_path().empty();
  const int width = picture.map_top_left_px.x() + w * picture.cell_px + 24 + kLegendWidth + kMargin;
  const int legend_height = (has_path ? 9 : 6) * kLegendRow + 60;
  const int height = picture.map_top_left_px.y() + std::max(h * picture.cell_px, legend_height) + kAxisBottom + kMargin;
  cv::Mat canvas(height, width, CV_8UC3, ToScalar(colours::kBackground));

  DrawCells(picture.grid, options.hillshade, picture.cell_px, picture.map_top_left_px, &canvas);
  DrawPath(picture, map.sensor_path(), &canvas);
  DrawAxes(picture, &canvas);
  DrawLegend(picture, options.hillshade, has_path, &canvas);

  Text(&canvas, options.title.empty() ? "SSTA map" : options.title, kMargin, kMargin + 14, 0.55);
  char subtitle[160];
  std::snprintf(subtitle, sizeof(subtitle), "%d x %d cells of %.2f m; %llu frames; classes for a vehicle stepping %.2f m",
                w, h, picture.grid.resolution_m, static_cast<unsigned long long>(map.frames_inserted()),
                map.metadata().vehicle.max_step_m);
  Text(&canvas, subtitle, kMargin, kMargin + 34, 0.4);
  picture.image = ToImage(canvas);
  return picture;
}

MapPicture ExportPicture(const TraversabilityMap& map, const std::string& path, const MapPictureOptions& options) {
  MapPicture picture = RenderMapPicture(map, options);
  WriteImageCompact(picture.image, path);
  return picture;
}

namespace {

/// The colour of a diff pixel: its change's, unchanged obstacles darker than unchanged ground.
Rgb8 ChangeRgb(CellChange change, std::uint8_t class_b) {
  namespace c = change_colours;
  switch (change) {
    case CellChange::kUnchanged:
      return class_b == static_cast<std::uint8_t>(TravClass::kNonTraversable) ? c::kUnchangedObstacle : c::kUnchanged;
    case CellChange::kNewObstacle: return c::kNewObstacle;
    case CellChange::kCleared: return c::kCleared;
    case CellChange::kHarder: return c::kHarder;
    case CellChange::kEasier: return c::kEasier;
    case CellChange::kNewlySeen: return c::kNewlySeen;
    case CellChange::kNoLongerSeen: return c::kNoLongerSeen;
    case CellChange::kUncertain: return c::kUncertain;
    default: return colours::kUnknown;
  }
}

}  // namespace

ImageRgb RenderMapDiffPicture(const MapDiff& diff, const std::string& title) {
  MapPicture picture;
  picture.grid.origin = diff.b.origin;
  picture.grid.resolution_m = diff.b.resolution_m;
  picture.grid.classes = diff.change;
  const int w = picture.grid.width();
  const int h = picture.grid.height();
  picture.cell_px = std::max(1, 1200 / std::max(1, std::max(w, h)));
  picture.map_top_left_px = Eigen::Vector2i(kMargin + kAxisLeft, kMargin + kTitleHeight);
  const int legend_rows = 12;
  const int width = picture.map_top_left_px.x() + w * picture.cell_px + 24 + kLegendWidth + 40 + kMargin;
  const int height = picture.map_top_left_px.y() + std::max(h * picture.cell_px, legend_rows * kLegendRow + 60) +
                     kAxisBottom + kMargin;
  cv::Mat canvas(height, width, CV_8UC3, ToScalar(colours::kBackground));

  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      const auto change = static_cast<CellChange>(diff.change(v, u));
      const Rgb8 c = ChangeRgb(change, diff.b.classes(v, u));
      for (int dv = 0; dv < picture.cell_px; ++dv) {
        const int y = picture.map_top_left_px.y() + v * picture.cell_px + dv;
        auto* row = canvas.ptr<cv::Vec3b>(y);
        for (int du = 0; du < picture.cell_px; ++du) {
          const int x = picture.map_top_left_px.x() + u * picture.cell_px + du;
          const Rgb8 px = change == CellChange::kNone && (x + y) % 6 == 0 ? colours::kUnknownHatch : c;
          row[x] = cv::Vec3b(px.r, px.g, px.b);
        }
      }
    }
  }
  DrawPath(picture, diff.path_a, &canvas);
  DrawPath(picture, diff.path_b, &canvas);
  DrawAxes(picture, &canvas);

  // The legend: every change with its count.
  const int x = picture.map_top_left_px.x() + w * picture.cell_px + 24;
  int y = picture.map_top_left_px.y();
  const auto count = [&](CellChange change) {
    return std::to_string(diff.summary.counts[static_cast<std::size_t>(change)]);
  };
  auto swatch = [&](const Rgb8& colour, bool hatched, const std::string& name) {
    cv::rectangle(canvas, cv::Rect(x, y, kSwatch, kSwatch), ToScalar(colour), cv::FILLED);
    if (hatched) cv::line(canvas, {x, y + kSwatch - 1}, {x + kSwatch - 1, y}, ToScalar(colours::kUnknownHatch), 1);
    cv::rectangle(canvas, cv::Rect(x, y, kSwatch, kSwatch), kInk, 1);
    Text(&canvas, name, x + kSwatch + 8, y + kSwatch - 2);
    y += kLegendRow;
  };
  namespace c = change_colours;
  swatch(c::kNewObstacle, false, "new obstacle " + count(CellChange::kNewObstacle));
  swatch(c::kCleared, false, "cleared " + count(CellChange::kCleared));
  swatch(c::kHarder, false, "harder (now semi) " + count(CellChange::kHarder));
  swatch(c::kEasier, false, "easier (was semi) " + count(CellChange::kEasier));
  swatch(c::kNewlySeen, false, "newly seen " + count(CellChange::kNewlySeen));
  swatch(c::kNoLongerSeen, false, "no longer seen " + count(CellChange::kNoLongerSeen));
  swatch(c::kUncertain, false, "uncertain " + count(CellChange::kUncertain));
  swatch(c::kUnchanged, false, "unchanged ground");
  swatch(c::kUnchangedObstacle, false, "unchanged obstacle");
  swatch(colours::kUnknown, true, "no class in either");
  if (!diff.path_a.empty() || !diff.path_b.empty()) {
    y += 4;
    cv::line(canvas, {x, y + kSwatch / 2}, {x + kSwatch + 4, y + kSwatch / 2}, ToScalar(colours::kPath), 2, cv::LINE_AA);
    Text(&canvas, "sensor paths", x + kSwatch + 8, y + kSwatch - 2);
    y += kLegendRow;
  }
  DrawScaleBar(picture, x, y, &canvas);

  Text(&canvas, title.empty() ? "SSTA map changes" : title, kMargin, kMargin + 14, 0.55);
  char subtitle[160];
  std::snprintf(subtitle, sizeof(subtitle), "%d x %d cells of %.2f m; %zu with a class in both maps, %zu real changes",
                w, h, picture.grid.resolution_m, diff.summary.compared, diff.summary.RealChanges());
  Text(&canvas, subtitle, kMargin, kMargin + 34, 0.4);
  return ToImage(canvas);
}

}  // namespace ssta
