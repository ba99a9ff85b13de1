#pragma once
// tinygltf as Strata compiles it (tinygltf_impl.cpp holds the one implementation): no image
// decoding or writing, no filesystem access at all, external images kept as names only.

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_FS
#define TINYGLTF_NO_EXTERNAL_IMAGE
#include <tiny_gltf.h>
