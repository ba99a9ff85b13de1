// The one translation unit that compiles Debian's tinyobjloader (header-only) for Strata.
#define TINYOBJLOADER_IMPLEMENTATION
#include <tiny_obj_loader.h>
