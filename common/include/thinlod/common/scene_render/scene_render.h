// Scene to renderer: the scene graph's lights and materials in the shared
// renderer's terms, so the simplifier's impostors and the frontend's
// reference frames are lit the same way.
//
// Contract:
// - sceneLighting(): every DirectionalLight/PointLight that is on, in world
//   space, at most render::kMaxLights (the first ones in scene order; the
//   rest are reported in `dropped`); ambient = sum of ambientIntensity*color
//   over lights plus a floor of 0.2 so unlit sides stay visible. A scene
//   without lights gets one headlight-like directional light (VRML's
//   default headlight, fixed along -Z) so that it is never black.
// - shapeMaterial(): VRML Material -> render::Material (diffuse,
//   transparency -> alpha, specular, shininess*128); no Material -> unlit
//   white, as VRML specifies.
// - Pure; no GL calls (only render's plain structs).
#pragma once

#include <cstddef>

#include "thinlod/common/render/camera.h"
#include "thinlod/common/render/mesh_renderer.h"
#include "thinlod/common/scene/scene.h"

namespace thinlod::scene {

render::Lighting sceneLighting(const Scene& scene, std::size_t* dropped = nullptr);
render::Material shapeMaterial(const ShapeNode& shape);

}  // namespace thinlod::scene
