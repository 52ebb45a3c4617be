// The C interface of the OpenImageIO module (libflashgs_image_oiio.so), which image_io.cpp loads at the first EXR/TIFF/JPEG write or PNG/EXR read.
#pragma once

#include <cstddef>

// Kept out of the programs' link: OpenImageIO pulls ~260 shared libraries (OpenCV, FFmpeg,
// GDAL, ...) into every process that links it, which cost each start 0.3-0.6 s before main().
// Each function returns 0 on success, else writes a message of at most error_size bytes
// into `error` and returns non-zero. No exception crosses this interface.
extern "C" {

// Whether OpenImageIO has a writer for `path`'s format (its extension).
int flashgs_oiio_can_write(const char* path);

// Writes a width x height image of 3 channels (floats when is_float, else bytes) in the format
// `path` names, onto the descriptor `fd` (an I/O proxy) or, for a plugin without proxies, to
// the file `temp_path` by name. *write_errno gets the first errno value a write on `fd` met.
int flashgs_oiio_write(const char* path, int fd, const char* temp_path, int width, int height, int is_float,
                       const void* pixels, int* write_errno, char* error, std::size_t error_size);

// Reads `path` as floats into the buffer take(context, width, height, channels) returns
// (width * height * channels floats).
int flashgs_oiio_read(const char* path, float* (*take)(void* context, int width, int height, int channels),
                      void* context, char* error, std::size_t error_size);

}
