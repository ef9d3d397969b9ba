#include "convert.h"

namespace handsim::py_convert {

Array as_array(py::handle obj, const std::string& argument) {
  if (obj.is_none() || py::isinstance<py::str>(obj))
    throw py::type_error(argument + ": expected an array of numbers, got " +
                         std::string(py::str(py::type::of(obj).attr("__name__"))));
  Array a = Array::ensure(obj);  // null (error cleared) when obj cannot become a float64 array
  if (!a)
    throw py::type_error(argument + ": expected an array of numbers, got " +
                         std::string(py::str(py::type::of(obj).attr("__name__"))));
  return a;
}

bool to_flag(py::handle obj, const std::string& argument) {
  if (PyBool_Check(obj.ptr())) return obj.ptr() == Py_True;
  if (py::isinstance(obj, py::module_::import("numpy").attr("bool_"))) return obj.cast<bool>();
  throw py::type_error(argument + ": expected True or False, got " +
                       std::string(py::str(py::type::of(obj).attr("__name__"))));
}

IntArray as_int_array(py::handle obj, const std::string& argument) {
  auto type_name = [&] { return std::string(py::str(py::type::of(obj).attr("__name__"))); };
  if (obj.is_none() || py::isinstance<py::str>(obj))
    throw py::type_error(argument + ": expected an array of integers, got " + type_name());
  py::array a = py::array::ensure(obj);
  if (!a) throw py::type_error(argument + ": expected an array of integers, got " + type_name());
  const char kind = a.dtype().kind();
  if (kind != 'i' && kind != 'u' && a.size() > 0)
    throw py::type_error(argument + ": expected an array of integers, got dtype " +
                         std::string(py::str(a.dtype())));
  return IntArray::ensure(a);
}

std::string shape_str(const py::array& a) {
  std::string s = "(";
  for (py::ssize_t i = 0; i < a.ndim(); ++i) s += std::to_string(a.shape(i)) + (a.ndim() == 1 ? "," : i + 1 < a.ndim() ? ", " : "");
  return s + ")";
}

void require_shape(const py::array& a, std::vector<py::ssize_t> shape, const std::string& argument) {
  bool ok = a.ndim() == py::ssize_t(shape.size());
  for (size_t i = 0; ok && i < shape.size(); ++i) ok = shape[i] < 0 || a.shape(i) == shape[i];
  if (ok) return;
  std::string want = "(";
  for (size_t i = 0; i < shape.size(); ++i)
    want += (shape[i] < 0 ? std::string("N") : std::to_string(shape[i])) +
            (shape.size() == 1 ? "," : i + 1 < shape.size() ? ", " : "");
  throw py::value_error(argument + ": expected shape " + want + "), got " + shape_str(a));
}

Vec3 to_vec3(py::handle obj, const std::string& argument) {
  Array a = as_array(obj, argument);
  require_shape(a, {3}, argument);
  return Vec3(a.at(0), a.at(1), a.at(2));
}

Quat to_quat(py::handle obj, const std::string& argument) {
  Array a = as_array(obj, argument);
  require_shape(a, {4}, argument);
  return Quat(a.at(3), a.at(0), a.at(1), a.at(2));  // Eigen's constructor takes w first
}

Pose to_pose(py::handle obj, const std::string& argument) {
  Array a = as_array(obj, argument);
  require_shape(a, {7}, argument);
  return {Vec3(a.at(0), a.at(1), a.at(2)), Quat(a.at(6), a.at(3), a.at(4), a.at(5))};
}

std::vector<Vec3> to_points(py::handle obj, const std::string& argument) {
  Array a = as_array(obj, argument);
  require_shape(a, {-1, 3}, argument);
  std::vector<Vec3> out(a.shape(0));
  auto r = a.unchecked<2>();
  for (py::ssize_t i = 0; i < a.shape(0); ++i) out[i] = Vec3(r(i, 0), r(i, 1), r(i, 2));
  return out;
}

py::array_t<double> from_vec3(const Vec3& v) {
  py::array_t<double> a(3);
  for (int k = 0; k < 3; ++k) a.mutable_at(k) = v[k];
  return a;
}

py::array_t<double> from_quat(const Quat& q) {
  py::array_t<double> a(4);
  for (int k = 0; k < 4; ++k) a.mutable_at(k) = q.coeffs()[k];  // coeffs() is x,y,z,w
  return a;
}

py::array_t<double> from_pose(const Pose& p) {
  py::array_t<double> a(7);
  for (int k = 0; k < 3; ++k) a.mutable_at(k) = p.position[k];
  for (int k = 0; k < 4; ++k) a.mutable_at(3 + k) = p.orientation.coeffs()[k];
  return a;
}

}  // namespace handsim::py_convert
