#pragma once
/// CPU integrators (cpu/ray_marcher.h's march), registered in integrators():
///   "ray-marcher" — S looked up trilinearly in the frame's radiance volume at each step (the
///                   integrator of every radiance-volume method; its GPU variant is the slice
///                   marcher in gpu/);
///   "exact"       — S traced at each step towards every light with step delta1 (no radiance
///                   volume): the reference;
///   "light-space-march", "radial-blur" — the whole methods of the same names
///                   (cpu/light_space_march.h, cpu/radial_blur.h).

namespace scatterlab {

/// Registers the CPU variants of "ray-marcher", "exact", "light-space-march" and "radial-blur".
void registerIntegrators();

}  // namespace scatterlab
