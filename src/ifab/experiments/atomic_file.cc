#include "ifab/experiments/atomic_file.h"

#include <unistd.h>

#include "ifab/core/error.h"

namespace ifab::experiments {

AtomicOfstream::AtomicOfstream(std::filesystem::path path)
    : path_(std::move(path)), exceptions_at_start_(std::uncaught_exceptions()) {
  // Unique per process and target: parallel runs write different folders, one process one file.
  temp_ = path_;
  temp_ += ".tmp." + std::to_string(::getpid());
  open(temp_, std::ios::out | std::ios::trunc | std::ios::binary);
  IFAB_THROW_UNLESS(is_open(), "{}: cannot write the file", path_.string());
}

void AtomicOfstream::Commit() {
  if (done_) return;
  done_ = true;
  flush();
  const bool ok = good();
  close();
  std::error_code ec;
  if (!ok) {
    std::filesystem::remove(temp_, ec);
    ThrowInputError("{}: write failed (the previous file, if any, is kept)", path_.string());
  }
  std::filesystem::rename(temp_, path_, ec);
  if (ec) {
    std::filesystem::remove(temp_, ec);
    ThrowInputError("{}: cannot replace the file: {}", path_.string(), ec.message());
  }
}

AtomicOfstream::~AtomicOfstream() {
  if (done_) return;
  if (std::uncaught_exceptions() > exceptions_at_start_) {
    done_ = true;
    close();
    std::error_code ec;
    std::filesystem::remove(temp_, ec);
    return;
  }
  try {
    Commit();
  } catch (const std::exception&) {
    // A destructor cannot throw; the target is untouched and the temporary removed.
  }
}

void WriteFileAtomically(const std::filesystem::path& path, const std::string& text) {
  AtomicOfstream out(path);
  out << text;
  out.Commit();
}

}  // namespace ifab::experiments
