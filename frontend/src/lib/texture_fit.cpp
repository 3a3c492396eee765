#include "texture_fit.h"

#include <algorithm>
#include <cmath>
#include <cassert>
#include <cstdint>
#include <cstring>

namespace thinlod::frontend::detail {

RgbaImage shrinkImage(const RgbaImage& source, int width, int height) {
  assert(width >= 1 && height >= 1 && width <= source.width && height <= source.height &&
         "shrinkImage: target must be non-empty and no larger than the source");
  RgbaImage out(width, height);
  for (int y = 0; y < height; ++y) {
    const int y0 = static_cast<int>(static_cast<long long>(y) * source.height / height);
    const int y1 =
        std::max(y0 + 1, static_cast<int>(static_cast<long long>(y + 1) * source.height / height));
    for (int x = 0; x < width; ++x) {
      const int x0 = static_cast<int>(static_cast<long long>(x) * source.width / width);
      const int x1 =
          std::max(x0 + 1, static_cast<int>(static_cast<long long>(x + 1) * source.width / width));
      // Premultiplied sums so transparent texels do not darken the edges.
      std::uint64_t rgb[3] = {0, 0, 0};
      std::uint64_t alpha = 0;
      std::uint64_t count = 0;
      for (int sy = y0; sy < y1; ++sy) {
        for (int sx = x0; sx < x1; ++sx) {
          const std::uint8_t* p = source.at(sx, sy);
          for (int c = 0; c < 3; ++c) rgb[c] += static_cast<std::uint64_t>(p[c]) * p[3];
          alpha += p[3];
          ++count;
        }
      }
      std::uint8_t* q = out.at(x, y);
      for (int c = 0; c < 3; ++c) {
        q[c] = alpha == 0 ? 0 : static_cast<std::uint8_t>((rgb[c] + alpha / 2) / alpha);
      }
      q[3] = static_cast<std::uint8_t>((alpha + count / 2) / count);
    }
  }
  return out;
}

namespace {

// `source`, or `storage` holding it shrunk so that no side exceeds the layer.
const RgbaImage* shrunkToLayer(const RgbaImage& source, int layerSize, RgbaImage& storage) {
  if (source.width <= layerSize && source.height <= layerSize) return &source;
  storage =
      shrinkImage(source, std::min(source.width, layerSize), std::min(source.height, layerSize));
  return &storage;
}

}  // namespace

FittedTexture fitTextureToLayer(const RgbaImage& source, int layerSize) {
  assert(layerSize >= 1 && source.consistent() && !source.empty());
  FittedTexture fitted;
  if (source.width == layerSize && source.height == layerSize) {
    fitted.useSource = true;
    return fitted;
  }
  RgbaImage shrunk;
  const RgbaImage* image = shrunkToLayer(source, layerSize, shrunk);
  const int w = image->width;
  const int h = image->height;
  fitted.uvScale = glm::vec2(static_cast<float>(w) / layerSize, static_cast<float>(h) / layerSize);
  const int padRight = w < layerSize ? 1 : 0;
  const int padTop = h < layerSize ? 1 : 0;
  if (padRight == 0 && padTop == 0) {
    fitted.image = std::move(shrunk);
    return fitted;
  }
  RgbaImage padded(w + padRight, h + padTop);
  const std::size_t rowBytes = static_cast<std::size_t>(w) * 4;
  for (int y = 0; y < padded.height; ++y) {
    const int sourceRow = std::max(0, y - padTop);  // the extra top row repeats row 0
    std::memcpy(padded.at(0, y), image->at(0, sourceRow), rowBytes);
    if (padRight != 0) std::memcpy(padded.at(w, y), image->at(w - 1, sourceRow), 4);
  }
  fitted.image = std::move(padded);
  return fitted;
}

FittedTexture fitRepeatingTextureToLayer(const RgbaImage& source, int layerSize) {
  assert(layerSize >= 1 && source.consistent() && !source.empty());
  FittedTexture fitted;
  if (source.width == layerSize && source.height == layerSize) {
    fitted.useSource = true;
    return fitted;
  }
  RgbaImage shrunk;
  const RgbaImage* image = shrunkToLayer(source, layerSize, shrunk);
  if (image->width == layerSize && image->height == layerSize) {
    fitted.image = std::move(shrunk);
    return fitted;
  }
  // Bilinear enlargement, texel centres aligned, neighbours wrapping around.
  const int w = image->width;
  const int h = image->height;
  RgbaImage out(layerSize, layerSize);
  for (int y = 0; y < layerSize; ++y) {
    const float sy = (static_cast<float>(y) + 0.5f) * static_cast<float>(h) / layerSize - 0.5f;
    const int y0 = static_cast<int>(std::floor(sy));
    const float fy = sy - static_cast<float>(y0);
    const int ya = (y0 % h + h) % h;
    const int yb = ((y0 + 1) % h + h) % h;
    for (int x = 0; x < layerSize; ++x) {
      const float sx = (static_cast<float>(x) + 0.5f) * static_cast<float>(w) / layerSize - 0.5f;
      const int x0 = static_cast<int>(std::floor(sx));
      const float fx = sx - static_cast<float>(x0);
      const int xa = (x0 % w + w) % w;
      const int xb = ((x0 + 1) % w + w) % w;
      const std::uint8_t* p00 = image->at(xa, ya);
      const std::uint8_t* p10 = image->at(xb, ya);
      const std::uint8_t* p01 = image->at(xa, yb);
      const std::uint8_t* p11 = image->at(xb, yb);
      std::uint8_t* o = out.at(x, y);
      for (int c = 0; c < 4; ++c) {
        const float top = p00[c] + (p10[c] - p00[c]) * fx;
        const float bottom = p01[c] + (p11[c] - p01[c]) * fx;
        o[c] = static_cast<std::uint8_t>(std::lround(std::clamp(top + (bottom - top) * fy, 0.0f, 255.0f)));
      }
    }
  }
  fitted.image = std::move(out);
  return fitted;
}

}  // namespace thinlod::frontend::detail
