# Layering check (run by CTest): the engine includes no HTTP or JSON header, and only the files
# of the acceleration layer include Embree; clients/ speaks HTTP only, except the embedded
# transport of `strata play --embedded`, the one file that may include the engine and the
# protocol layer (every client file may include the shared header-only vocabulary below). Usage: cmake -DROOT=<repo> -P check_layering.cmake
cmake_minimum_required(VERSION 3.25)
set(EMBREE_ALLOWED
    engine/accel/embree_device.cpp
    engine/accel/blas_pool.cpp
    engine/accel/blas_store.cpp
    engine/accel/embree_tlas.cpp
    engine/accel/instance_transform.cpp
    engine/accel/lod_scenes.cpp
    engine/accel/instance_array.cpp
    engine/accel/clustered_blas.cpp
    engine/accel/embree_trace.h
    engine/accel/incremental_tlas.cpp
    engine/accel/dynamic_tier.cpp
    engine/accel/tlas_merge.cpp)
file(GLOB_RECURSE ENGINE_FILES RELATIVE "${ROOT}" "${ROOT}/engine/*.h" "${ROOT}/engine/*.cpp")
set(problems "")
foreach(f IN LISTS ENGINE_FILES)
    file(READ "${ROOT}/${f}" text)
    if(text MATCHES "#include[ \t]*[<\"](httplib\\.h|nlohmann/)")
        string(APPEND problems "  ${f} includes an HTTP or JSON header\n")
    endif()
    if(text MATCHES "#include[ \t]*[<\"]embree3/" AND NOT f IN_LIST EMBREE_ALLOWED)
        string(APPEND problems "  ${f} includes Embree outside the acceleration layer\n")
    endif()
endforeach()
set(EMBEDDED_ALLOWED
    clients/cli/embedded_transport.cpp)
# Header-only vocabulary with no engine behaviour, shared by every layer: the one value-or-error
# type (and the invariant check it uses).
set(SHARED_HEADERS engine/core/expected.h engine/core/check.h)
file(GLOB_RECURSE CLIENT_FILES RELATIVE "${ROOT}" "${ROOT}/clients/*.h" "${ROOT}/clients/*.cpp")
foreach(f IN LISTS CLIENT_FILES)
    file(READ "${ROOT}/${f}" text)
    if(f IN_LIST EMBEDDED_ALLOWED)
        continue()
    endif()
    string(REGEX MATCHALL "#include[ \t]*[<\"](engine|protocol|server)/[^>\"]*" includes "${text}")
    foreach(inc IN LISTS includes)
        string(REGEX REPLACE "^#include[ \t]*[<\"]" "" header "${inc}")
        if(NOT header IN_LIST SHARED_HEADERS)
            string(APPEND problems "  ${f} includes ${header} (engine, protocol or server layer)\n")
        endif()
    endforeach()
endforeach()
if(problems)
    message(FATAL_ERROR "layering violations:\n${problems}")
endif()
list(LENGTH ENGINE_FILES n)
list(LENGTH CLIENT_FILES m)
message(STATUS "layering ok: ${n} engine files and ${m} client files checked")
