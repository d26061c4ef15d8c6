#include "groundslam/io/TextParsing.hpp"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <sstream>

#include "groundslam/io/InputError.hpp"

namespace groundslam {

std::string trim(const std::string& text) {
  const auto begin = text.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return "";
  const auto end = text.find_last_not_of(" \t\r\n");
  return text.substr(begin, end - begin + 1);
}

std::vector<double> parseNumbers(const std::string& line, const std::string& file, int line_number) {
  std::istringstream words(line);
  std::vector<double> numbers;
  std::string word;
  while (words >> word) {
    char* end = nullptr;
    const double value = std::strtod(word.c_str(), &end);
    if (end == word.c_str() || *end != '\0' || !std::isfinite(value)) {
      throw InputError(file + ":" + std::to_string(line_number) + ": not a number: '" + word + "'");
    }
    numbers.push_back(value);
  }
  return numbers;
}

std::vector<std::string> splitCsvRow(const std::string& line) {
  std::vector<std::string> cells;
  std::stringstream row(line);
  for (std::string cell; std::getline(row, cell, ',');) cells.push_back(cell);
  return cells;
}

bool naturalLess(const std::string& a, const std::string& b) {
  size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool digit_a = std::isdigit(static_cast<unsigned char>(a[i])) != 0;
    const bool digit_b = std::isdigit(static_cast<unsigned char>(b[j])) != 0;
    if (digit_a && digit_b) {
      size_t end_a = i, end_b = j;
      while (end_a < a.size() && std::isdigit(static_cast<unsigned char>(a[end_a]))) ++end_a;
      while (end_b < b.size() && std::isdigit(static_cast<unsigned char>(b[end_b]))) ++end_b;
      std::string run_a = a.substr(i, end_a - i), run_b = b.substr(j, end_b - j);
      run_a.erase(0, std::min(run_a.find_first_not_of('0'), run_a.size()));
      run_b.erase(0, std::min(run_b.find_first_not_of('0'), run_b.size()));
      if (run_a.size() != run_b.size()) return run_a.size() < run_b.size();
      if (run_a != run_b) return run_a < run_b;
      i = end_a;
      j = end_b;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  return a.size() - i < b.size() - j;
}

}  // namespace groundslam
