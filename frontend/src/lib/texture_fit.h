// Private: fitting an arbitrary RGBA texture into one square layer of the
// frontend's array textures. Pure CPU.
#pragma once

#include <glm/vec2.hpp>

#include "thinlod/common/core/rgba_image.h"

namespace thinlod::frontend::detail {

struct FittedTexture {
  // What to write at the layer's uv-origin corner. Empty when `source` can be
  // written unchanged (it is exactly layerSize x layerSize).
  RgbaImage image;
  // uv * uvScale addresses the texture inside the layer.
  glm::vec2 uvScale{1.0f};
  bool useSource = false;
};

// Shrinks a texture larger than the layer (alpha-weighted box filter, per
// axis) and, when the result is smaller than the layer, adds one replicated
// column on the right and one replicated row on top so bilinear filtering at
// the edge never reads texels left in the layer by an earlier texture.
// Precondition: source consistent and non-empty, layerSize >= 1.
FittedTexture fitTextureToLayer(const RgbaImage& source, int layerSize);

// A texture that repeats (a mesh's base-colour texture: uvs may leave
// [0, 1], glTF's and VRML's default wrap is repeat): resampled to fill the
// whole layer (uvScale 1) so the layer's repeat wrap tiles it. Larger sides
// shrink as fitTextureToLayer does; smaller ones are enlarged bilinearly with
// wrap-around neighbours (the texture tiles).
// Precondition: source consistent and non-empty, layerSize >= 1.
FittedTexture fitRepeatingTextureToLayer(const RgbaImage& source, int layerSize);

// Alpha-weighted box filter to width x height (each <= the source's edge).
RgbaImage shrinkImage(const RgbaImage& source, int width, int height);

}  // namespace thinlod::frontend::detail
