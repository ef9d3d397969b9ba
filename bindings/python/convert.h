// numpy <-> core conversions with strict shape checks. Every converter names the argument it checks, so
// a wrong shape reads "pose: expected shape (7,), got (3,)".
#pragma once

#include "handsim/tables.h"
#include "handsim/types.h"

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <algorithm>
#include <string>
#include <vector>

namespace handsim::py_convert {

namespace py = pybind11;
using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
using IntArray = py::array_t<int64_t, py::array::c_style | py::array::forcecast>;

// Converts to a float64 array, or raises TypeError naming the argument.
Array as_array(py::handle obj, const std::string& argument);
// Converts an integer array (any integer dtype; an empty sequence too) to int64, or raises TypeError naming
// the argument: floats are not silently truncated into indices.
IntArray as_int_array(py::handle obj, const std::string& argument);
// Raises ValueError unless the array has exactly this shape (-1 matches any length).
void require_shape(const py::array& a, std::vector<py::ssize_t> shape, const std::string& argument);
std::string shape_str(const py::array& a);

Vec3 to_vec3(py::handle obj, const std::string& argument);
Quat to_quat(py::handle obj, const std::string& argument);  // x,y,z,w; normalisation is the core's job
Pose to_pose(py::handle obj, const std::string& argument);  // (7,): x,y,z, qx,qy,qz,qw
std::vector<Vec3> to_points(py::handle obj, const std::string& argument);  // (N,3)

// Every array the module returns is a fresh copy. A method's result belongs to the caller and is writable;
// an attribute's array (frame.positions, body_def.pose, ...) is read-only, because a write into it looks like
// a change of the object but could never reach it: frame.positions[0, 0] = 99 raises "assignment destination
// is read-only" instead of being silently lost. a.copy() gives a writable one; assigning the whole
// attribute (body_def.pose = p) changes the object where it has a setter.
template <class A>
A read_only(A a) {
  py::detail::array_proxy(a.ptr())->flags &= ~py::detail::npy_api::NPY_ARRAY_WRITEABLE_;
  return a;
}

py::array_t<double> from_vec3(const Vec3& v);
py::array_t<double> from_quat(const Quat& q);
py::array_t<double> from_pose(const Pose& p);

// A column-major Rows x N Eigen matrix has the memory layout of a row-major (N, Rows) array: one copy each way.
template <class Scalar, int Rows>
py::array_t<Scalar> from_columns(const Eigen::Matrix<Scalar, Rows, Eigen::Dynamic>& m) {
  py::array_t<Scalar> a({py::ssize_t(m.cols()), py::ssize_t(m.rows())});
  std::copy(m.data(), m.data() + m.size(), a.mutable_data());
  return a;
}
// (N, Rows) array (already shape-checked) -> Rows x N matrix.
template <class Scalar, int Rows, class In>
Eigen::Matrix<Scalar, Rows, Eigen::Dynamic> to_columns(const py::array_t<In, py::array::c_style | py::array::forcecast>& a) {
  Eigen::Matrix<Scalar, Rows, Eigen::Dynamic> m(Rows, a.shape(0));
  std::transform(a.data(), a.data() + a.size(), m.data(), [](In v) { return Scalar(v); });
  return m;
}

// A bound C++ object (id, enum, def struct) or TypeError naming the argument: "body: expected a BodyId, got int".
template <class T>
T cast_arg(py::handle obj, const std::string& argument) {
  if (!py::isinstance<T>(obj))
    throw py::type_error(argument + ": expected a " +
                         std::string(py::str(py::detail::get_type_handle(typeid(T), true).attr("__name__"))) +
                         ", got " + std::string(py::str(py::type::of(obj).attr("__name__"))));
  return obj.cast<T>();
}

// Python lets None, 0 or "" stand for a bool; a flag set to any of them is a mistake worth naming, so flags
// take exactly True or False (a numpy bool too): "BodyDef.kinematic: expected True or False, got NoneType".
bool to_flag(py::handle obj, const std::string& argument);

template <class T>
void flag_property(py::class_<T>& cls, const char* name, bool T::*field, const std::string& argument,
                   const char* doc = "") {
  cls.def_property(
      name, [field](const T& self) { return self.*field; },
      [field, argument](T& self, py::handle v) { self.*field = to_flag(v, argument); }, doc);
}

// Builds a default T and assigns each keyword as an attribute, so `BodyDef(mass=2)` works for every def
// struct; an unknown keyword is a TypeError naming it. A value of the wrong type goes through the field's
// setter, whose message names Class.field (handsim/argument_errors.py replaces pybind11's generic one).
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

// A Python enum named `type` with every value of the enum table (handsim/enum_table.h) whose type it is, under
// its UPPER name, so no value can be missing from Python (the table's Python test walks them all).
template <class E>
py::enum_<E> bind_enum(py::module_& m, const char* type, const char* doc = "") {
  py::enum_<E> e(m, type, doc);
  int count = 0;
  for (const EnumValue& row : kEnumValues)
    if (std::string(row.type) == type) e.value(row.upper, E(row.value)), ++count;
  if (count == 0) throw std::logic_error(std::string("bind_enum: no enum table rows for ") + type);
  return e;
}

}  // namespace handsim::py_convert
