// RgbaImage: the one plain 8-bit RGBA raster of thinlod, exchanged between
// the renderer (readback), the impostor builder, the texture codecs
// (codec/encoding.h encodes and decodes it), the wire conversion and the
// frontend. Header-only, part of the core: no GL types, no dependencies.
//
// Contract:
// - pixels.size() == width * height * 4; rows are stored top-down (row 0 is
//   the top of the picture), 4 bytes per pixel in R, G, B, A order.
//   consistent() checks this (and non-negative sizes); code taking an image
//   from outside checks it before indexing.
// - Colours are non-premultiplied; alpha 0 means "no surface here".
// - Value type: copy/move freely, no thread affinity.
#pragma once

#include <cassert>
#include <cstddef>
#include <cstdint>
#include <vector>

namespace thinlod {

struct RgbaImage {
  int width = 0;
  int height = 0;
  std::vector<std::uint8_t> pixels;  // top-down rows, RGBA8

  RgbaImage() = default;
  // Precondition: w, h >= 0 (sizes from outside are checked before this).
  RgbaImage(int w, int h)
      : width(w),
        height(h),
        pixels(static_cast<std::size_t>(checkedSide(w)) * checkedSide(h) * 4, 0) {}

  bool empty() const { return width <= 0 || height <= 0; }
  // Every alpha is 255 (true for an image without pixels).
  bool opaque() const {
    for (std::size_t i = 3; i < pixels.size(); i += 4) {
      if (pixels[i] != 255) return false;
    }
    return true;
  }
  bool consistent() const {
    return width >= 0 && height >= 0 &&
           pixels.size() == static_cast<std::size_t>(width) * static_cast<std::size_t>(height) * 4;
  }
  // Pointer to the 4 bytes of pixel (x, y), y counted from the top. Asserts nothing: caller checks.
  std::uint8_t* at(int x, int y) {
    return pixels.data() + (static_cast<std::size_t>(y) * width + x) * 4;
  }
  const std::uint8_t* at(int x, int y) const {
    return pixels.data() + (static_cast<std::size_t>(y) * width + x) * 4;
  }

 private:
  static int checkedSide(int side) {
    assert(side >= 0 && "RgbaImage: negative size");
    return side < 0 ? 0 : side;  // release builds: an empty image, not a huge allocation
  }
};

}  // namespace thinlod
