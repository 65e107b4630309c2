// Prints the time per 640 x 480 frame of the normal methods and the segmentation. Measures
// only; asserts nothing about speed (machines differ), so it cannot make the suite flaky.
#include <cstdio>
#include <ctime>

#include <gtest/gtest.h>

#include "geometry/synthetic_scene.h"
#include "ssta/geometry/normal_estimator.h"
#include "ssta/geometry/segmenter.h"

namespace ssta {
namespace {

// Processor time per call [ms] (std::clock: not inflated when other processes share the cores).
template <typename F>
double MillisecondsPerCall(int repeats, F f) {
  f();  // warm-up: allocates the reused buffers
  const std::clock_t start = std::clock();
  for (int i = 0; i < repeats; ++i) f();
  return 1000.0 * static_cast<double>(std::clock() - start) / CLOCKS_PER_SEC / repeats;
}

TEST(GeometryTiming, PrintsMillisecondsPer640x480Frame) {
  const test::PinholeCamera camera;
  test::Scene scene = test::GroundScene(1.0);
  scene.AddBox({-0.6, 0.7, 3.0}, {0.6, 1.0, 4.0});
  scene.AddPlane({0, 0, -1}, 20.0);  // a wall closing the view at 20 m
  Image3f cloud = scene.Render(camera, nullptr, 30.0);
  test::AddDepthNoise(0.15 / (camera.f_px * camera.baseline_m), 5, &cloud);
  const ImageF disparity = test::DisparityOf(cloud, camera);
  constexpr int kRepeats = 20;

  Image3f normals;
  for (const NormalMethod method :
       {NormalMethod::kCovarianceMatrix, NormalMethod::kAverage3dGradient,
        NormalMethod::kAverageDepthChange}) {
    NormalOptions options;
    options.method = method;
    NormalEstimator estimator(options);
    const double ms = MillisecondsPerCall(kRepeats, [&] { estimator.Compute(cloud); });
    std::printf("[ timing ] normals %-22s %7.2f ms/frame (CPU)\n", NormalMethodName(method), ms);
    RecordProperty(std::string("normals_") + NormalMethodName(method) + "_ms", std::to_string(ms));
    if (method == NormalMethod::kCovarianceMatrix) normals = estimator.Compute(cloud);
  }
  Segmenter segmenter(SegmenterOptions{});
  const double ms = MillisecondsPerCall(kRepeats, [&] { segmenter.Compute(normals, &disparity); });
  std::printf("[ timing ] segmentation                  %7.2f ms/frame (CPU) (%d segments)\n", ms,
              segmenter.Compute(normals, &disparity).num_segments());
  RecordProperty("segmentation_ms", std::to_string(ms));
}

}  // namespace
}  // namespace ssta
