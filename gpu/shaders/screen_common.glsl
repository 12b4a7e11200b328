// Shared by the per-pixel competitors' passes (jittered-march, froxel): the camera's rays
// (Camera::RayGenerator::at, core/camera.h), the density with the box test of Grid3::sample,
// and interleaved gradient noise (shading/screen_march.h). After common.glsl.
uniform vec3 uForward;
uniform vec3 uRight;
uniform vec3 uUp;
uniform vec2 uTanHalf;  // (tan(fov/2)·aspect, tan(fov/2))
uniform vec2 uSize;     // image width, height
uniform float uAlbedo;

#ifdef SL_OBJECTS
// The surface pass (gpu/stages.h ScreenSurfaces), at full resolution: the first surface's
// view-ray distance (3e38 where none) and its L_p.
layout(binding = BINDING_SURFACE_TEXTURE) uniform sampler2D uSurfaceDistance;
layout(binding = BINDING_SURFACE_RADIANCE_TEXTURE) uniform sampler2D uSurfaceRadiance;
#endif

// The view-ray distance of the first surface at full-resolution pixel p; kInf where none (and
// always without objects).
float surfaceDistance(ivec2 p) {
#ifdef SL_OBJECTS
  float t = texelFetch(uSurfaceDistance, min(p, ivec2(uSize) - 1), 0).r;
  return t < 1.0e38 ? t : kInf;
#else
  return kInf;
#endif
}

// The ray through continuous image coordinates f (x right, y down), in the CPU's arithmetic
// (cpuCameraRay, cpu_arithmetic.glsl): the same direction bit for bit, so that the
// pixel's box entry, exit and step count are the CPU's, and a ray passing a lamp passes it at
// the CPU's distance.
vec3 cameraRay(vec2 f) { return cpuCameraRay(f, uSize, uForward, uRight, uUp, uTanHalf); }

// Grid3::sample: zero outside the box (inclusive faces), trilinear inside.
float densityAt(vec3 x) {
  if (any(lessThan(x, uBoxMin)) || any(greaterThan(x, uBoxMax))) return 0.0;
  return densityAtIndex(x * uDensityScale + uDensityOffset);
}

float interleavedGradientNoise(ivec2 p) {
  float f = 0.06711056 * float(p.x) + 0.00583715 * float(p.y);
  float g = 52.9829189 * (f - floor(f));
  return g - floor(g);
}
