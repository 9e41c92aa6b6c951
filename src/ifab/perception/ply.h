#pragma once
/// \file
/// PLY point clouds (Stanford polygon format), as read and written by CloudCompare, MeshLab and
/// Open3D: element `vertex` with float or double x, y, z and any further scalar properties (read
/// into PointCloud fields; e.g. origin_x/y/z, the laser centre of each point). ASCII and binary
/// (little- and big-endian) are read; other elements (faces, lists) are skipped. A malformed file
/// gives an InputError naming the file, the line or vertex, and what was expected.

#include <iosfwd>
#include <string>

#include "ifab/perception/cloud.h"

namespace ifab {

enum class PlyFormat { kAscii, kBinaryLittleEndian, kBinaryBigEndian };

struct PlyWriteOptions {
  PlyFormat format{PlyFormat::kBinaryLittleEndian};  ///< binary: compact and exact
  bool double_precision{false};  ///< x, y, z and fields as double (else float, ~1 um at 10 m)
  std::string comment;           ///< written as a header comment
};

/// Read a PLY file. Throws InputError if it cannot be read or is malformed.
PointCloud ReadPly(const std::string& path);
/// Read PLY data from a stream; `name` stands for the file in messages.
PointCloud ReadPly(std::istream& in, const std::string& name);

/// Write PLY data to a stream. (The module writes no files: experiments/ply_file.h saves one.)
void WritePly(std::ostream& out, const PointCloud& cloud, const PlyWriteOptions& options = {});

}  // namespace ifab
