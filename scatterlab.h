#pragma once
/// The one header a program using scatterlab includes, as <openvdb/openvdb.h> or
/// <mitsuba/mitsuba.h>:
///
///   #include <scatterlab/scatterlab.h>
///
/// It forwards to api/scatterlab.h (initialize, loadScene, createMethod, Renderer, images and
/// metrics). Installed as <prefix>/include/scatterlab/scatterlab.h; in the build tree it is
/// reached through <build>/include/scatterlab, a link to the source root.

#include "api/scatterlab.h"
