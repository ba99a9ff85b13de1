# Version check (run by CTest): `PROGRAM --version` exits 0, writes nothing to stderr and prints
# exactly "NAME VERSION" and a newline, VERSION being project(VERSION) of the top CMakeLists.txt,
# the one place the version is written. Usage:
#   cmake -DPROGRAM=<binary> -DNAME=<name> -DVERSION=<version> -P check_version.cmake
cmake_minimum_required(VERSION 3.25)
execute_process(COMMAND "${PROGRAM}" --version
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
if(NOT rc STREQUAL "0")
    message(FATAL_ERROR "${NAME} --version exited with '${rc}'\nstdout: ${out}\nstderr: ${err}")
endif()
if(NOT out STREQUAL "${NAME} ${VERSION}\n")
    message(FATAL_ERROR "${NAME} --version printed '${out}', expected '${NAME} ${VERSION}\\n'")
endif()
if(NOT err STREQUAL "")
    message(FATAL_ERROR "${NAME} --version wrote to stderr: ${err}")
endif()
message(STATUS "${NAME} --version: ${VERSION}")
