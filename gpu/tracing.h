#pragma once
/// What every tracing pass of gpu/ binds (the lights, the density, the medium's uniforms of
/// common.glsl) and the scene objects on the GPU for one frame: their shadow maps and the
/// surface pass of the camera. Every function needs a GL context (gpu::context()).

#include <memory>
#include <vector>

#include "core/stages.h"
#include "gpu/objects.h"
#include "gpu/records.h"
#include "gpu/shadow_maps.h"
#include "gpu/timer.h"
#include "gpu/volume.h"

namespace scatterlab::gpu {

/// The scene's lights as the shaders read them (GpuLight[] at BINDING_LIGHTS), with the lamp
/// model's k_l of `density` in lamp.x and min_l m_l at its box's diagonal in lights[0].lamp.y
/// (lamp_k.comp.glsl; only where a point or spot light is inside the box, else k_l 0 and the
/// minimum 1 as packed). Kept on the density volume (Volume::lights) while the lights, σt and
/// the volume stay the same.
struct DeviceLights {
  std::vector<GpuLight>
      packed;  ///< as uploaded (packLight: lampK 0, lampMin 1), the key with sigmaT
  float sigmaT = 0.0f;
  Buffer buffer;
  /// A's far field of these lights in this density (render.far_field; gpu::ViewMarchGpu): its
  /// grid, kept with them while R and the lamp model stay, so a frame whose lights did not move
  /// (a camera move: the far field is isotropic) runs no far-field pass. RGBA32F, a texel per
  /// vertex (gpu/bindings.h kFarFieldTexture).
  mutable Texture farField;
  mutable float farFieldRadius = 0.0f;  ///< R the grid was built with; 0: none
  mutable bool farFieldLamp = false;    ///< whether its terms hold the lamp model
  mutable IVec3 farFieldDims{0};        ///< its vertices per axis
  mutable int farFieldUpdates = 0;      ///< in-place updates since it was built whole
  /// The lights a step of each brick evaluates (far_mask.comp.glsl), made with the grid.
  mutable Buffer farMask;
  /// The lights these replaced where those had a far field (deviceLights): held until the view
  /// march takes their grid over and updates it light by light (gpu::ViewMarchGpu), or drops
  /// them; never a chain (their own `before` is dropped when they are replaced).
  mutable std::shared_ptr<const DeviceLights> before;
};

/// The lights of `scene` for `density`: the volume's kept ones where they are the same, else
/// uploaded and (with a lamp inside the box) completed by the lamp model's pass, timed on
/// `timer`; the pass leaves its program in use.
std::shared_ptr<const DeviceLights> deviceLights(const Scene& scene, const Volume& density,
                                                 StageTimer* timer);

/// The steps of a march across the medium box's diagonal at step `step` (stepCount, common.glsl),
/// plus one: the most a ray through the box takes. For lightDispatches (gpu/shaders.h): a shadow
/// ray's at delta1 is `perLight` of a pass that traces each light at each step (froxel,
/// jittered-march, per-voxel's S; the one is the light loop's own iteration), a view ray's at
/// the march's step the steps of the factored view march.
double diagonalSteps(const Scene& scene, float step);

/// Buffers and uniforms every tracing shader (common.glsl) needs: the lights SSBO
/// (binding::kLights), the density texture (binding::kDensityTexture), phase, σt, Δ1, eye. Needs
/// a current context.
class TracingInputs {
 public:
  /// `shadows`: the scene objects' shadow maps (null without objects); programs that trace
  /// with these inputs must then be built with addShadowVariant(shadows(), ...).
  /// The lights come from deviceLights(): where they changed and a point or spot light is inside
  /// the density's box, that runs the lamp model's pass (timed on `timer`) and leaves another
  /// program in use, so make the program current after this.
  TracingInputs(const Scene& scene, const Volume& density, float delta1,
                const ShadowMaps* shadows = nullptr, StageTimer* timer = nullptr);
  /// Shadow rays that jump over blocks of zero density (programs built with
  /// addShadowRaySkip): builds the density's empty-space grid (gpu/empty_space.h) unless it is
  /// built, so call it before the program is made current; apply() then binds it.
  void skipEmptySpace(StageTimer* timer);
  /// Binds the buffers and texture and sets the uniforms of `program` (which must be in use).
  void apply(const Program& program) const;
  /// The lights apply() binds (deviceLights()).
  const DeviceLights& lights() const { return *lights_; }
  const ShadowMaps* shadows() const { return shadows_; }

 private:
  const Scene& scene_;
  const Volume& density_;
  float delta1_;
  const ShadowMaps* shadows_;
  std::shared_ptr<const DeviceLights> lights_;
  const Texture* blockMax_ = nullptr;
};

/// The scene objects on the GPU for one frame: their triangles and shadow maps (both null
/// without objects). Built once per render by the first stage that needs them.
struct SceneShadows {
  std::unique_ptr<ObjectGeometry> geometry;
  std::unique_ptr<ShadowMaps> maps;
  /// Uploads the objects and renders the maps when the scene has objects and they are not
  /// built yet; returns maps (null without objects). Needs the context.
  const ShadowMaps* build(const Scene& scene, const ShadowMapSettings& settings, StageTimer* timer);
};

/// The surface pass (docs/objects.md "GPU"): the scene's objects rasterised from the camera
/// with a depth buffer (surface.frag.glsl). Per pixel, the first surface's
/// L_p = albedo/π·Σ_l E_l·max(0, n·ω_l)·V_l·T(p, l) (V_l from the shadow maps, T marched with
/// the step of `inputs`) goes into the rgb of `color` (RGBA32F, the camera's size) with alpha 0,
/// after `color` was cleared to (background, 1); its view-ray distance goes into `distance`
/// (R32F, 3e38 where no surface), and its depth into `depth` (the depth range nearD..farD of
/// the camera's projection). The slice marcher composites over `color` with `depth` as its
/// depth buffer; the per-pixel methods (gpu/light_space_march.h, gpu/radial_blur.h,
/// gpu/screen_march.h) read `distance` and `color` (ScreenSurfaces). Needs the context, `objects`
/// built and `inputs` made with its maps.
struct SurfacePass {
  Texture distance;
  Texture depth;
  float nearD = 1.0f, farD = 2.0f;
};
SurfacePass renderSurfaces(const Scene& scene, const SceneShadows& objects,
                           const TracingInputs& inputs, const Texture& color, StageTimer* timer);

/// The surface pass as the per-pixel methods read it (built only when the scene has objects):
/// its L_p image and distances, bound at binding::kSurfaceRadianceTexture and
/// binding::kSurfaceTexture (the samplers uSurfaceRadiance and uSurfaceDistance of shaders
/// compiled with SL_OBJECTS: light_space_march, radial_blur, screen_common).
struct ScreenSurfaces {
  Texture radiance;
  SurfacePass pass;
  bool built = false;
  /// Runs the surface pass when `objects` has maps (the scene has objects), else does nothing.
  void build(const Scene& scene, const SceneShadows& objects, const TracingInputs& inputs,
             StageTimer* timer);
  /// Binds the two textures (when built).
  void bind() const;
};

}  // namespace scatterlab::gpu
