// The one translation unit that compiles Debian's tinygltf (header-only) with Strata's settings,
// so that it is built with the same sanitizers and fuzzing instrumentation as the importers.
// tinygltf 2.7 uses std::ofstream in its (unused) writers even under TINYGLTF_NO_FS.
#include <fstream>

#define TINYGLTF_IMPLEMENTATION
#include "protocol/assets/tinygltf_config.h"
