#pragma once
// The consumer's own core/scene.h (issue 36): an engine with a src/core/scene.h of its own,
// first on its include path. scatterlab's installed headers include each other as
// <scatterlab/core/scene.h>, so this file is never taken for theirs; before, the package put
// include/scatterlab on the path and its "core/scene.h" found this one ('Scene' does not name a
// type).
namespace engine {
struct Scene {
  int entities = 3;
};
}  // namespace engine
