// Primitive encoding of the map files (map_file.hpp): trivially copyable values in host byte order,
// doubles checked finite on the way in, truncation reported with what was being read. Private to
// libs/map (map_file.cpp, map_file_lidar.cpp).
#pragma once

#include "livo/common/so3.hpp"

#include <cmath>
#include <istream>
#include <ostream>
#include <stdexcept>
#include <string>
#include <type_traits>

namespace livo::map_codec {

template <class T>
void put(std::ostream& os, const T& v) {
  static_assert(std::is_trivially_copyable<T>::value, "POD only");
  os.write(reinterpret_cast<const char*>(&v), sizeof(T));
}

template <class T>
T get(std::istream& is, const char* what) {
  static_assert(std::is_trivially_copyable<T>::value, "POD only");
  T v;
  if (!is.read(reinterpret_cast<char*>(&v), sizeof(T)))
    throw std::runtime_error(std::string("truncated while reading ") + what);
  return v;
}

inline void putVec(std::ostream& os, const Eigen::Ref<const Eigen::VectorXd>& v) {
  for (Eigen::Index i = 0; i < v.size(); ++i) put(os, v[i]);
}

inline double getFinite(std::istream& is, const char* what) {
  const double v = get<double>(is, what);
  if (!std::isfinite(v)) throw std::runtime_error(std::string("non-finite ") + what);
  return v;
}

inline Vec3 getVec3(std::istream& is, const char* what) {
  Vec3 v;
  for (int i = 0; i < 3; ++i) v[i] = getFinite(is, what);
  return v;
}

}  // namespace livo::map_codec
