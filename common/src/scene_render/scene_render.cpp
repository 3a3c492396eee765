#include "thinlod/common/scene_render/scene_render.h"

#include <algorithm>
#include <glm/geometric.hpp>

namespace thinlod::scene {

render::Lighting sceneLighting(const Scene& scene, std::size_t* dropped) {
  render::Lighting lighting;
  lighting.ambient = glm::vec3(0.2f);
  std::size_t droppedCount = 0;
  for (const NodeInstance& instance : flattenInstances(scene)) {
    render::Light light;
    float ambient = 0.0f;
    glm::vec3 color(1.0f);
    if (const auto* directional = instance.node->as<DirectionalLightNode>()) {
      if (!directional->on) continue;
      light.type = render::Light::Type::kDirectional;
      light.vector = glm::normalize(
          glm::vec3(instance.contentToWorld * glm::vec4(directional->direction, 0.0f)));
      color = directional->color * directional->intensity;
      ambient = directional->ambientIntensity;
      light.color = color;
    } else if (const auto* point = instance.node->as<PointLightNode>()) {
      if (!point->on) continue;
      light.type = render::Light::Type::kPoint;
      light.vector = glm::vec3(instance.contentToWorld * glm::vec4(point->location, 1.0f));
      color = point->color * point->intensity;
      ambient = point->ambientIntensity;
      light.color = color;
      light.attenuation = point->attenuation.y;  // linear term; VRML's constant term is 1
    } else {
      continue;
    }
    if (lighting.lights.size() >= static_cast<std::size_t>(render::kMaxLights)) {
      ++droppedCount;
      continue;
    }
    lighting.ambient += ambient * color;
    lighting.lights.push_back(light);
  }
  if (lighting.lights.empty()) {
    render::Light headlight;
    headlight.type = render::Light::Type::kDirectional;
    headlight.vector = glm::vec3(0.0f, 0.0f, -1.0f);
    lighting.lights.push_back(headlight);
  }
  lighting.ambient = glm::min(lighting.ambient, glm::vec3(1.0f));
  if (dropped != nullptr) *dropped = droppedCount;
  return lighting;
}

render::Material shapeMaterial(const ShapeNode& shape) {
  render::Material material;
  if (!shape.appearance.hasMaterial) {
    material.lit = false;
    material.diffuse = glm::vec4(1.0f);
    return material;
  }
  const Material& vrml = shape.appearance.material;
  material.lit = true;
  material.diffuse = glm::vec4(vrml.diffuseColor, 1.0f - std::clamp(vrml.transparency, 0.0f, 1.0f));
  material.specular = vrml.specularColor;
  material.shininess = std::max(1.0f, vrml.shininess * 128.0f);
  if (vrml.transparency > 0.0f) material.alphaMode = render::AlphaMode::kBlend;
  return material;
}

}  // namespace thinlod::scene
