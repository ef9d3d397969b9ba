// numpy <-> core conversions with strict shape checks. Every converter names the argument it checks, so
// a wrong shape reads "pose: expected shape (7,), got (3,)".
#pragma once

#include "handsim/types.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>
#include <vector>

namespace handsim::py_convert {

namespace py = pybind11;
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;

// Converts to a float64 array, or raises TypeError naming the argument.
Array as_array(py::handle obj, const std::string& argument);
// Raises ValueError unless the array has exactly this shape (-1 matches any length).
void require_shape(const Array& a, std::vector<py::ssize_t> shape, const std::string& argument);
std::string shape_str(const Array& a);

Vec3 to_vec3(py::handle obj, const std::string& argument);
Quat to_quat(py::handle obj, const std::string& argument);  // x,y,z,w; normalisation is the core's job
Pose to_pose(py::handle obj, const std::string& argument);  // (7,): x,y,z, qx,qy,qz,qw
std::vector<Vec3> to_points(py::handle obj, const std::string& argument);  // (N,3)

py::array_t<double> from_vec3(const Vec3& v);
py::array_t<double> from_quat(const Quat& q);
py::array_t<double> from_pose(const Pose& p);

// Builds a default T and assigns each keyword as an attribute, so `BodyDef(mass=2)` works for every def
// struct and an unknown keyword is a TypeError naming it.
template <class T>
T from_kwargs(const py::kwargs& kwargs, const char* type_name) {
  py::object obj = py::cast(T());
  for (auto item : kwargs) {
    std::string key = py::str(item.first);
    if (!py::hasattr(obj, key.c_str()))
      throw py::type_error(std::string(type_name) + "() got an unexpected keyword argument '" + key + "'");
    py::setattr(obj, key.c_str(), item.second);
  }
  return obj.cast<T>();
}

}  // namespace handsim::py_convert
