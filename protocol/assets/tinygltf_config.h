#pragma once
// tinygltf as Strata compiles it (tinygltf_impl.cpp holds the one implementation): no image
// decoding or writing, no filesystem access at all (external buffers and images are read through
// the callbacks gltf_import.cpp installs, from the upload's side files only).

#define TINYGLTF_NO_STB_IMAGE
#define TINYGLTF_NO_STB_IMAGE_WRITE
#define TINYGLTF_NO_FS
#include <tiny_gltf.h>
