// Natural ordering of file names, so an image folder plays "2.jpg" before "10.jpg".
#pragma once

#include <string>
#include <vector>

namespace toposlam {

/// True when a sorts before b in natural order (digit runs compare by value, the rest by character).
bool naturalLess(const std::string& a, const std::string& b);
void sortNatural(std::vector<std::string>& names);

}  // namespace toposlam
