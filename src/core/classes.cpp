#include "ssta/core/classes.h"

#include <algorithm>
#include <cmath>

namespace ssta {

std::string_view ClassName(TravClass c) {
  switch (c) {
    case TravClass::kUnknown: return "unknown";
    case TravClass::kTraversable: return "traversable";
    case TravClass::kSemiTraversable: return "semi-traversable";
    case TravClass::kNonTraversable: return "non-traversable";
    case TravClass::kUndecided: return "undecided";
  }
  return "invalid";
}

Rgb8 ClassColour(TravClass c) {
  switch (c) {
    case TravClass::kTraversable: return {0, 255, 0};
    case TravClass::kSemiTraversable: return {0, 0, 255};
    case TravClass::kNonTraversable: return {255, 0, 0};
    default: return {0, 0, 0};
  }
}

TravClass Worse(TravClass a, TravClass b) {
  const auto ia = static_cast<int>(a);
  const auto ib = static_cast<int>(b);
  SSTA_CHECK(ia >= 1 && ia <= 3 && ib >= 1 && ib <= 3, "Worse() takes classes 1..3");
  return static_cast<TravClass>(std::max(ia, ib));
}

ImageRgb MakeOverlay(const ImageU8& grey, const ImageU8& labels, float alpha) {
  SSTA_CHECK(grey.width() == labels.width() && grey.height() == labels.height(),
             "overlay image and labels differ in size");
  ImageRgb out(grey.width(), grey.height());
  for (std::size_t i = 0; i < grey.size(); ++i) {
    const float g = grey[i];
    const auto label = static_cast<TravClass>(labels[i]);
    Rgb8 px{grey[i], grey[i], grey[i]};
    if (label == TravClass::kUnknown) {
      const auto d = static_cast<std::uint8_t>(std::lround(g * 0.35f));
      px = {d, d, d};
    } else if (labels[i] >= 1 && labels[i] <= 3) {
      const Rgb8 c = ClassColour(label);
      auto mix = [&](std::uint8_t channel) {
        return static_cast<std::uint8_t>(std::lround((1.0f - alpha) * g + alpha * channel));
      };
      px = {mix(c.r), mix(c.g), mix(c.b)};
    }
    out[i] = px;
  }
  return out;
}

ImageRgb ColourizeLabels(const ImageU8& labels) {
  ImageRgb out(labels.width(), labels.height());
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const std::uint8_t l = labels[i];
    if (l == kDontCare) {
      out[i] = {255, 255, 255};
    } else if (l == static_cast<std::uint8_t>(TravClass::kUndecided)) {
      out[i] = {128, 128, 128};
    } else if (l <= 3) {
      out[i] = ClassColour(static_cast<TravClass>(l));
    } else {
      out[i] = {255, 0, 255};
    }
  }
  return out;
}

}  // namespace ssta
