#include "methods/backend.h"

#include <algorithm>
#include <cmath>

namespace weathergs::methods {

int RunFraction::at(int iterations) const {
  return std::max(1, int(std::lround(double(num) * iterations / den)));
}

std::vector<int> snapshot_iterations(const std::vector<RunFraction>& snapshots, int iterations) {
  std::vector<int> out;
  for (const RunFraction& f : snapshots)
    if (const int it = f.at(iterations); it < iterations) out.push_back(it);
  return out;
}

std::vector<int> scored_snapshots(const std::vector<RunFraction>& snapshots, int iterations) {
  std::vector<int> its = snapshot_iterations(snapshots, iterations);
  std::sort(its.begin(), its.end());
  its.erase(std::unique(its.begin(), its.end()), its.end());
  return its;
}

}  // namespace weathergs::methods
