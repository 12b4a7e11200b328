#include "gpu/empty_space.h"

#include "core/max_density_grid.h"
#include "gpu/bindings.h"
#include "gpu/dispatch.h"
#include "gpu/shaders.h"

namespace scatterlab::gpu {

IVec3 blockCount(const Volume& density) {
  constexpr int B = MaxDensityGrid::kBlock;
  return (density.dims + IVec3(B - 1)) / IVec3(B);
}

ProgramVariant& addShadowRaySkip(ProgramVariant& variant) {
  variant.prepend("block_walk.glsl");
  return variant.define("SL_SKIP_SHADOWS");
}

const Texture& blockMaxGrid(const Volume& density, StageTimer* timer) {
  if (density.blockMax) return *density.blockMax;
  const IVec3 blocks = blockCount(density);
  auto grid = std::make_shared<Texture>(
      Texture::make3D(GL_R32F, blocks.x, blocks.y, blocks.z, "empty-space grid",
                      Texture::Contents::Overwritten));  // one store per block
  const Program& p =
      program({.compute = {"common.glsl", "block_max.comp.glsl"}}, "empty-space grid");
  p.use();
  glBindTextureUnit(binding::kDensityTexture, density.texture.id());
  setIVec3(p, "uDensityDims", density.dims);
  setIVec3(p, "uBlockCount", blocks);
  glBindImageTexture(binding::kBlockMaxImage, grid->id(), 0, GL_TRUE, 0, GL_WRITE_ONLY, GL_R32F);
  dispatch("empty-space grid", {groups(blocks.x, 4), groups(blocks.y, 4), groups(blocks.z, 4)},
           timer);
  glMemoryBarrier(GL_TEXTURE_FETCH_BARRIER_BIT);
  density.blockMax = std::move(grid);
  return *density.blockMax;
}

}  // namespace scatterlab::gpu
