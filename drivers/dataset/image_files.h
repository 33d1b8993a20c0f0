#pragma once

// Image files of the dataset readers: reading and decoding the PNGs of RGB-D datasets and
// describing images in error messages. Internal to cblox_dataset.

#include <cstdint>
#include <string>

#include <opencv2/core.hpp>

#include "core/geometry/image.h"

namespace cblox {

/// Describes the pixel type of `image` for messages, e.g. "16-bit with 1 channel(s)".
/// Thread-safe (no shared state).
std::string describeImageType(const cv::Mat& image);

/// "<width>x<height>", e.g. "640x480". Thread-safe (no shared state).
std::string describeSize(int width, int height);

/// Returns true if `image` is width x height. Otherwise returns false and writes
/// "<path>: size <w>x<h> does not match <expected> <width>x<height>" to *error (if non-null),
/// `expected` naming what the size should match, e.g. "the intrinsics'".
/// Thread-safe (no shared state).
bool checkImageSize(const std::string& path, const cv::Mat& image, int width, int height,
                    const std::string& expected, std::string* error);

/// Reads a 16-bit single-channel depth image into *units (non-null) without decoding its
/// values. Returns false and writes a message starting with the path to *error (if non-null)
/// when the file is missing, unreadable, or of another pixel type; the last message reads
/// "<path>: depth image must be <requirement>, got <type>". Thread-safe (no shared state).
bool readDepthUnits(const std::string& path, const std::string& requirement, cv::Mat* units,
                    std::string* error);

/// Decodes a CV_16UC1 depth image to metres: each value times metres_per_unit, except 0 and
/// invalid_units (both "no measurement"), which become 0. Thread-safe (no shared state).
DepthImage depthFromUnits(const cv::Mat& units, double metres_per_unit, uint16_t invalid_units = 0);

/// Converts a CV_8UC3 image in OpenCV's BGR channel order (as cv::imread gives) to RGB.
/// Thread-safe (no shared state).
ColorImage colorFromBgr(const cv::Mat& bgr);

/// Reads an 8-bit single-channel (grey) image, as stored, into *image (non-null). Returns
/// false and writes "<path>: image is missing", "<path>: cannot read image" or "<path>: image
/// must be 8-bit single-channel (grey), got <type>" to *error (if non-null) otherwise.
/// Thread-safe (no shared state).
bool readGrayImage(const std::string& path, cv::Mat* image, std::string* error);

/// Reads an 8-bit colour image of size width x height into *color (non-null) as RGB. Returns
/// false, leaving *color untouched, and writes a message starting with the path to *error (if
/// non-null) when the file is missing or unreadable as colour, or its size differs (the
/// message as checkImageSize's with `expected`). Thread-safe (no shared state).
bool readColorImage(const std::string& path, int width, int height, const std::string& expected,
                    ColorImage* color, std::string* error);

}  // namespace cblox
