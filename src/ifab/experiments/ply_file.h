#pragma once
/// \file
/// A PLY file written in full or not at all (atomic_file.h): the file side of perception/ply.h,
/// whose module writes no files.

#include <string>

#include "ifab/perception/ply.h"

namespace ifab {

/// Write `cloud` to `path`. Throws InputError if it cannot be written; a previous file at `path`
/// is then kept as it was.
void SavePly(const std::string& path, const PointCloud& cloud, const PlyWriteOptions& options = {});

}  // namespace ifab
