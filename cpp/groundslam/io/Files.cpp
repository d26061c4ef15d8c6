#include "groundslam/io/Files.hpp"

#include <filesystem>
#include <fstream>
#include <sstream>

#include "groundslam/io/InputError.hpp"

namespace groundslam {

void writeFileAtomically(const std::string& path, const std::string& content) {
  const std::string partial = path + ".partial";
  {
    std::ofstream out(partial, std::ios::binary | std::ios::trunc);
    if (!out) throw InputError(path + ": cannot open for writing");
    out << content;
    if (!out.flush()) throw InputError(path + ": write failed");
  }
  std::error_code error;
  std::filesystem::rename(partial, path, error);
  if (error) throw InputError(path + ": cannot move into place: " + error.message());
}

std::string readTextFile(const std::string& path) {
  if (!std::filesystem::exists(path)) throw InputError(path + ": no such file");
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path + ": cannot open for reading");
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

}  // namespace groundslam
