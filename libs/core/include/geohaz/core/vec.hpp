#pragma once
/// \file vec.hpp
/// Small fixed-size vector and tensor types used by all models (Eigen, double precision).

#include <Eigen/Core>

namespace geohaz {

/// A point or vector in Dim dimensions (2 for plane strain / map view, 3 for 3D).
template <int Dim>
using Vec = Eigen::Matrix<double, Dim, 1>;

/// A Dim x Dim tensor (stress, strain rate, spin).
template <int Dim>
using Mat = Eigen::Matrix<double, Dim, Dim>;

using Vec2 = Vec<2>;
using Vec3 = Vec<3>;
using Mat2 = Mat<2>;
using Mat3 = Mat<3>;

}  // namespace geohaz
