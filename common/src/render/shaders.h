// Private: the shader source of MeshRenderer (GLSL 3.30 core), compiled once
// per variant. A variant fixes what used to be per-pixel uniform branches
// (lit or not, textured or not, alpha mode) with #defines: on a software
// rasteriser (llvmpipe) every pixel pays for both sides of a uniform branch,
// which made the frontend's frames 1.6x the cost of a bare draw.
#pragma once

namespace thinlod::render {

// Vertex attribute locations, shared with the vertex layout in mesh_renderer.cpp.
constexpr unsigned kAttributePosition = 0;
constexpr unsigned kAttributeNormal = 1;
constexpr unsigned kAttributeUv = 2;
constexpr unsigned kAttributeColor = 3;
constexpr unsigned kAttributeLayer = 4;
constexpr unsigned kAttributeSkin = 5;  // skinned meshes: (bone A, bone B, weight of B)
// Texture unit of the bone matrices' buffer texture (unit 0 is the colour texture).
constexpr unsigned kBoneTextureUnit = 1;

// Prepended to both stages: "#version 330 core\n", then one line per define:
// LIT, SPECULAR, TEXTURED, VERTEX_COLORS, VERTEX_LAYERS, SKINNED (0/1); ALPHA_MODE (0 opaque:
// alpha written as 1; 1 mask: discard below the cutoff, alpha written as 1;
// 2 blend: alpha as computed); LIGHT_COUNT (0..4) and LIGHT_TYPES (int[4]
// constructor, 0 directional, 1 point), constants so the light loop unrolls.
inline constexpr const char* kMeshVertexShader = R"GLSL(
layout(location = 0) in vec3 aPosition;
layout(location = 1) in vec3 aNormal;
layout(location = 2) in vec2 aUv;
layout(location = 3) in vec4 aColor;
layout(location = 4) in float aLayer;

uniform mat4 uModel;
uniform mat4 uViewProjection;
uniform mat3 uNormalMatrix;

#if SKINNED
// ASLOD's two-bone rule, P = (1 - s) T_A P_A + s T_B P_B (anim::deform is the
// CPU reference): bone matrices are four RGBA32F texels (columns) each in a
// buffer texture, so the palette's size is not bounded by uniform space.
layout(location = 5) in vec3 aSkin;
uniform samplerBuffer uBones;
mat4 boneMatrix(float bone) {
  int base = int(bone) * 4;
  return mat4(texelFetch(uBones, base), texelFetch(uBones, base + 1),
              texelFetch(uBones, base + 2), texelFetch(uBones, base + 3));
}
#endif

#if LIT
out vec3 vWorldPosition;
out vec3 vNormal;
#endif
#if TEXTURED
out vec2 vUv;
#endif
#if VERTEX_LAYERS
flat out float vLayer;
#endif
#if VERTEX_COLORS
out vec4 vColor;
#endif

void main() {
  vec3 position = aPosition;
  vec3 normal = aNormal;
#if SKINNED
  mat4 boneA = boneMatrix(aSkin.x);
  mat4 boneB = boneMatrix(aSkin.y);
  position = mix((boneA * vec4(aPosition, 1.0)).xyz, (boneB * vec4(aPosition, 1.0)).xyz, aSkin.z);
  // The bones' linear parts blended (exact for rotations and uniform scales).
  normal = mix(mat3(boneA) * aNormal, mat3(boneB) * aNormal, aSkin.z);
#endif
  vec4 world = uModel * vec4(position, 1.0);
#if LIT
  vWorldPosition = world.xyz;
  vNormal = uNormalMatrix * normal;
#endif
#if TEXTURED
  vUv = aUv;
#endif
#if VERTEX_LAYERS
  vLayer = aLayer;
#endif
#if VERTEX_COLORS
  vColor = aColor;
#endif
  gl_Position = uViewProjection * world;
}
)GLSL";

inline constexpr const char* kMeshFragmentShader = R"GLSL(
#if LIT
in vec3 vWorldPosition;
in vec3 vNormal;
#endif
#if TEXTURED
in vec2 vUv;
uniform sampler2DArray uTexture;
#endif
#if VERTEX_LAYERS
flat in float vLayer;
#elif TEXTURED
uniform float uLayer;
#endif
#if VERTEX_COLORS
in vec4 vColor;
#endif

uniform vec4 uDiffuse;
#if ALPHA_MODE == 1
uniform float uAlphaCutoff;
#endif
#if LIT
uniform vec3 uSpecular;
uniform float uShininess;
uniform vec3 uAmbient;
uniform vec3 uLightVector[4];
uniform vec3 uLightColor[4];
uniform float uLightAttenuation[4];
uniform vec3 uEyePosition;
#endif

out vec4 fragColor;

void main() {
  vec4 base = uDiffuse;
#if VERTEX_COLORS
  base *= vColor;
#endif
#if VERTEX_LAYERS
  base *= texture(uTexture, vec3(vUv, vLayer));
#elif TEXTURED
  base *= texture(uTexture, vec3(vUv, uLayer));
#endif
#if ALPHA_MODE == 1
  if (base.a < uAlphaCutoff) discard;
#endif
  vec3 color = base.rgb;
#if LIT
  vec3 n = normalize(vNormal);
  if (!gl_FrontFacing) n = -n;  // two-sided lighting for open meshes
#if SPECULAR
  vec3 toEye = normalize(uEyePosition - vWorldPosition);
#endif
  color = uAmbient * base.rgb;
  const int kLightTypes[4] = LIGHT_TYPES;
  for (int i = 0; i < LIGHT_COUNT; ++i) {
    vec3 toLight;
    float attenuation = 1.0;
    if (kLightTypes[i] == 0) {
      toLight = -normalize(uLightVector[i]);
    } else {
      vec3 d = uLightVector[i] - vWorldPosition;
      float distance2 = dot(d, d);
      toLight = d * inversesqrt(max(distance2, 1e-12));
      attenuation = 1.0 / (1.0 + uLightAttenuation[i] * distance2);
    }
    float lambert = max(dot(n, toLight), 0.0);
#if SPECULAR
    float specular = 0.0;
    if (lambert > 0.0) {
      specular = pow(max(dot(n, normalize(toLight + toEye)), 0.0), uShininess);
    }
    color += uLightColor[i] * attenuation * (lambert * base.rgb + specular * uSpecular);
#else
    color += uLightColor[i] * attenuation * (lambert * base.rgb);
#endif
  }
#endif
#if ALPHA_MODE == 2
  fragColor = vec4(color, base.a);
#else
  fragColor = vec4(color, 1.0);
#endif
}
)GLSL";

}  // namespace thinlod::render
