// Private: the single shader program of MeshRenderer (GLSL 3.30 core).
#pragma once

namespace thinlod::render {

// Vertex attribute locations, shared with the vertex layout in mesh_renderer.cpp.
constexpr unsigned kAttributePosition = 0;
constexpr unsigned kAttributeNormal = 1;
constexpr unsigned kAttributeUv = 2;
constexpr unsigned kAttributeColor = 3;
constexpr unsigned kAttributeLayer = 4;

inline constexpr const char* kMeshVertexShader = R"GLSL(#version 330 core
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec2 aUv;
layout(location = 3) in vec4 aColor;
layout(location = 4) in float aLayer;

uniform mat4 uModel;
uniform mat4 uViewProjection;
uniform mat3 uNormalMatrix;

out vec3 vWorldPosition;
out vec3 vNormal;
out vec2 vUv;
out vec4 vColor;
flat out float vLayer;

void main() {
  vec4 world = uModel * vec4(aPosition, 1.0);
  vWorldPosition = world.xyz;
  vNormal = uNormalMatrix * aNormal;
  vUv = aUv;
  vColor = aColor;
  vLayer = aLayer;
  gl_Position = uViewProjection * world;
}
)GLSL";

// Alpha modes: 0 opaque (alpha written as 1), 1 mask (discard below cutoff,
// alpha written as 1), 2 blend (alpha written as computed).
inline constexpr const char* kMeshFragmentShader = R"GLSL(#version 330 core
in vec3 vWorldPosition;
in vec3 vNormal;
in vec2 vUv;
in vec4 vColor;
flat in float vLayer;

uniform vec4 uDiffuse;
uniform vec3 uSpecular;
uniform float uShininess;
uniform int uLit;
uniform int uUseVertexColors;
uniform int uTextured;
uniform int uUseVertexLayer;
uniform float uLayer;
uniform int uAlphaMode;
uniform float uAlphaCutoff;
uniform sampler2DArray uTexture;

uniform vec3 uAmbient;
uniform int uLightCount;
uniform int uLightType[4];
uniform vec3 uLightVector[4];
uniform vec3 uLightColor[4];
uniform float uLightAttenuation[4];
uniform vec3 uEyePosition;

out vec4 fragColor;

void main() {
  vec4 base = uDiffuse;
  if (uUseVertexColors != 0) base *= vColor;
  if (uTextured != 0) {
    base *= texture(uTexture, vec3(vUv, uUseVertexLayer != 0 ? vLayer : uLayer));
  }
  if (uAlphaMode == 1 && base.a < uAlphaCutoff) discard;
  vec3 color = base.rgb;
  if (uLit != 0) {
    vec3 n = normalize(vNormal);
    if (!gl_FrontFacing) n = -n;  // two-sided lighting for open meshes
    vec3 toEye = normalize(uEyePosition - vWorldPosition);
    color = uAmbient * base.rgb;
    for (int i = 0; i < uLightCount; ++i) {
      vec3 toLight;
      float attenuation = 1.0;
      if (uLightType[i] == 0) {
        toLight = -normalize(uLightVector[i]);
      } else {
        vec3 d = uLightVector[i] - vWorldPosition;
        float distance2 = dot(d, d);
        toLight = d * inversesqrt(max(distance2, 1e-12));
        attenuation = 1.0 / (1.0 + uLightAttenuation[i] * distance2);
      }
      float lambert = max(dot(n, toLight), 0.0);
      float specular = 0.0;
      if (lambert > 0.0) {
        specular = pow(max(dot(n, normalize(toLight + toEye)), 0.0), uShininess);
      }
      color += uLightColor[i] * attenuation * (lambert * base.rgb + specular * uSpecular);
    }
  }
  fragColor = vec4(color, uAlphaMode == 2 ? base.a : 1.0);
}
)GLSL";

}  // namespace thinlod::render
