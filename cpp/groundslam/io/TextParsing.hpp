#pragma once
#include <string>
#include <vector>

namespace groundslam {

std::string trim(const std::string& text);
/// Whitespace-separated numbers of one line; throws InputError "FILE:LINE: not a number: 'x'".
std::vector<double> parseNumbers(const std::string& line, const std::string& file, int line_number);
/// The comma-separated cells of one CSV row (no quoting: groundslam's own CSV files have none).
std::vector<std::string> splitCsvRow(const std::string& line);
/// Less-than on file names that compares runs of digits by value ("img2" < "img10").
bool naturalLess(const std::string& a, const std::string& b);

}  // namespace groundslam
