#include "ifab/experiments/ply_file.h"

#include "ifab/experiments/atomic_file.h"

namespace ifab {

void SavePly(const std::string& path, const PointCloud& cloud, const PlyWriteOptions& options) {
  experiments::AtomicOfstream out(path);
  WritePly(out, cloud, options);
  out.Commit();
}

}  // namespace ifab
