#pragma once
/// scatterlab's public entry point: include this, call initialize() once, then load or build a
/// Scene, create a Method and render.
///
///   scatterlab::initialize();
///   scatterlab::Scene scene = scatterlab::loadScene("data/scenes/glow.json");
///   auto method = scatterlab::createMethod(scene, "exact", "cpu");
///   scatterlab::RenderResult r = method->render(scene, nullptr);
///   scatterlab::writeExr(r.image, "glow.exr");
///
/// Re-rendering while lights, camera or time change: scatterlab::Renderer (api/renderer.h).
/// Building a medium in code: the density models of media/procedural.h and media/dense_grid.h.

#include "api/renderer.h"
#include "core/error.h"
#include "core/image.h"
#include "core/method.h"
#include "core/metrics.h"
#include "core/scene.h"
#include "media/dense_grid.h"
#include "media/procedural.h"

namespace scatterlab {

/// Registers every built-in stage variant (density models, methods, ...). Idempotent and
/// thread-safe; call before loadScene, parseScene or createMethod (without it they throw a
/// ConfigError that says so). Renderer calls it itself.
void initialize();

/// Library version, "MAJOR.MINOR.PATCH".
const char* version();

}  // namespace scatterlab
