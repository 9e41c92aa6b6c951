#pragma once
/// \file
/// Result files written in full or not at all (issue 14): an AtomicOfstream writes to a
/// temporary file beside its target and renames it over the target when it goes out of scope
/// normally (a rename within one folder is atomic on POSIX). If it is destroyed while an
/// exception unwinds, or a write failed, the target is left as it was and the temporary removed.

#include <exception>
#include <filesystem>
#include <fstream>
#include <string>

namespace ifab::experiments {

class AtomicOfstream : public std::ofstream {
 public:
  explicit AtomicOfstream(std::filesystem::path path);
  ~AtomicOfstream() override;
  AtomicOfstream(const AtomicOfstream&) = delete;
  AtomicOfstream& operator=(const AtomicOfstream&) = delete;

  /// Close and rename now; throws InputError if the data could not be written.
  void Commit();
  const std::filesystem::path& path() const { return path_; }

 private:
  std::filesystem::path path_, temp_;
  int exceptions_at_start_{0};
  bool done_{false};
};

/// Write `text` to `path` atomically (temporary file, then rename).
void WriteFileAtomically(const std::filesystem::path& path, const std::string& text);

}  // namespace ifab::experiments
