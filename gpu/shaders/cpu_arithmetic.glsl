// The CPU's float arithmetic, bit for bit, where an ulp decides something. Every program sees
// this file (gpu::compileShader puts it before the program's own files, after the #defines and
// SCATTERLAB_GPU_IMPRECISE's prologue).
//
// GLSL lets a GPU's float division err by 2.5 ulp and its sqrt, inversesqrt, length and
// normalize by more, and lets it fuse a·b + c into one rounding; the CPU rounds each IEEE
// operation correctly, apart. An ulp of a view ray's direction or length then moves its step
// count across an edge (stepCount: the pixel's quadrature changes, ~1 % on a sharp medium), and
// near a lamp, where the radiance grows as 1/distance, moves the pixel by 1e-4 relative
// (docs/gpu.md, "The CPU's arithmetic where an ulp decides"). Here a division or square root
// is taken in double and rounded to float: a double result within a few units of a double's
// last place of the true one, rounded to float, is the correctly rounded float (53 >= 2·24 + 2
// bits, so double rounding is innocuous for / and √; a quotient of floats that is not a float
// midpoint lies at least 2^-49 of itself from one, a root 2^-51), which is the CPU's, on any GL
// 4.x device (doubles are core since 4.0). `precise` keeps the compiler from fusing or
// reordering what the CPU rounds twice. These set up rays (a camera ray, a shadow ray, a light's
// distance, a step count), never run per march step: a consumer GPU runs doubles at 1/32–1/64
// of the float rate.

float cpuDiv(float a, float b) { return float(double(a) / double(b)); }
float cpuSqrt(float x) { return float(sqrt(double(x))); }
// glm::dot's order: (a.x·b.x + a.y·b.y) + a.z·b.z, each product rounded.
float cpuDot(vec3 a, vec3 b) {
  precise float r = a.x * b.x + a.y * b.y + a.z * b.z;
  return r;
}
// glm::length: sqrt(v·v).
float cpuLength(vec3 v) { return cpuSqrt(cpuDot(v, v)); }
// glm::normalize: v · (1 / sqrt(v·v)).
vec3 cpuNormalize(vec3 v) {
  precise vec3 r = v * cpuDiv(1.0, cpuLength(v));
  return r;
}
// glm's vec3 / float: each component divided.
vec3 cpuDiv(vec3 v, float s) { return vec3(cpuDiv(v.x, s), cpuDiv(v.y, s), cpuDiv(v.z, s)); }

// stepCount (core/stages.h): the equal midpoint steps of at most `stepLen` (up to SL_STEP_SLACK
// longer) over a segment of `len`, so that an integer ratio does not round apart from the CPU's;
// the ratio in the CPU's arithmetic.
int stepCount(float len, float stepLen) {
  precise float r = cpuDiv(len, stepLen) - SL_STEP_SLACK;
  return max(1, int(ceil(r)));
}

// Camera::RayGenerator::at (core/camera.h): the unit ray through continuous image coordinates
// f (x right, y down) of an image `size` pixels wide and high, from the camera's frame and
// tanHalf = (tan(fov/2)·aspect, tan(fov/2)), as the CPU rounds it.
vec3 cpuCameraRay(vec2 f, vec2 size, vec3 forward, vec3 right, vec3 up, vec2 tanHalf) {
  precise float u = (cpuDiv(f.x, size.x) * 2.0 - 1.0) * tanHalf.x;
  precise float v = (1.0 - cpuDiv(f.y, size.y) * 2.0) * tanHalf.y;
  precise vec3 w = forward + u * right + v * up;
  return cpuNormalize(w);
}
