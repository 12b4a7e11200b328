#pragma once
/// A quick look at a volume file without a scene (`scatterlab render smoke.vdb`, as OpenVDB's
/// vdb_render does): the scene document that frames it, documented in docs/scene-format.md
/// ("Rendering a volume file without a scene").

#include <filesystem>
#include <string>

#include "core/params.h"
#include "core/scene.h"

namespace scatterlab {

/// The scene document around the volume file at `path`, read by the density model
/// `densityType` ("vdb": its grid named "density"; "sog"): the file as medium.density with its
/// own bounds; resolution 128; albedo 0.9; sigma_t chosen so that the 90th percentile of the
/// optical depths of the columns along the view axis that hold density is 3 (scale-free: the
/// same picture whatever the file's units and density scale); a camera on the −z side looking
/// at the box's centre along +z, far enough for the box's bounding sphere to fit the 40° view;
/// one directional light from above, the left and behind the camera; a dark background. The
/// document is an ordinary scene: `--set` overrides apply to it, and `scatterlab info --scene`
/// can print it. Throws what loading the density throws (IoError, ConfigError naming the keys).
Json quickLookScene(const std::string& path, const std::string& densityType);

/// The medium.density type that reads the file at `path` when it is a volume file (.vdb, .sog:
/// by its first bytes or extension; only regular files are looked into), else "".
std::string volumeFileType(const std::string& path);

/// The scene document of `path`: its JSON (readJsonFile), or, for a volume file
/// (volumeFileType), the quick-look scene that frames it. loadScene, Renderer::fromFile and
/// Python's Scene(path) read scenes through it.
Json readSceneDocument(const std::string& path);

/// Parses a `medium` object alone (its density file loaded). Key paths in errors start with
/// "medium".
Medium parseMediumDocument(const Json& medium, const std::filesystem::path& baseDir);

}  // namespace scatterlab
