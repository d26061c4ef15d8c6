#include "groundslam/io/Files.hpp"

#include <fcntl.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "groundslam/io/InputError.hpp"

namespace fs = std::filesystem;

namespace groundslam {
namespace {

[[noreturn]] void failWith(const std::string& path, const std::string& what, int error) {
  throw InputError(path + ": " + what + ": " + std::strerror(error));
}

/// Writes everything, retrying partial writes and interrupted calls.
void writeAll(int fd, const std::string& content, const std::string& path) {
  size_t written = 0;
  while (written < content.size()) {
    const ssize_t n = ::write(fd, content.data() + written, content.size() - written);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) failWith(path, "write failed", errno);
    written += static_cast<size_t>(n);
  }
}

}  // namespace

void writeNewFile(const std::string& path, const std::string& content) {
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_NOFOLLOW | O_CLOEXEC, 0644);
  if (fd < 0) {
    const int error = errno;
    failWith(path, error == EEXIST ? "exists already (not overwritten)" : "cannot create", error);
  }
  try {
    writeAll(fd, content, path);
    if (::fsync(fd) != 0) failWith(path, "cannot sync to disk", errno);
  } catch (...) {
    ::close(fd);
    ::unlink(path.c_str());
    throw;
  }
  if (::close(fd) != 0) {
    const int error = errno;
    ::unlink(path.c_str());
    failWith(path, "write failed", error);
  }
}

void writeFileAtomically(const std::string& path, const std::string& content) {
  static std::atomic<unsigned> counter{0};
  const std::string partial = path + ".partial-" + std::to_string(::getpid()) + "-" + std::to_string(counter++);
  writeNewFile(partial, content);
  if (::rename(partial.c_str(), path.c_str()) != 0) {
    const int error = errno;
    ::unlink(partial.c_str());
    failWith(path, "cannot move into place", error);
  }
  const fs::path parent = fs::path(path).parent_path();
  syncFolder(parent.empty() ? "." : parent.string());
}

void syncFolder(const std::string& path) {
  const int fd = ::open(path.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);
  ::close(fd);
}

std::string readTextFile(const std::string& path) {
  std::error_code error;
  if (!fs::exists(path, error)) throw InputError(path + ": no such file");
  if (fs::is_directory(path, error)) throw InputError(path + ": is a folder, not a file");
  std::ifstream in(path, std::ios::binary);
  if (!in) failWith(path, "cannot open for reading", errno);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace groundslam
