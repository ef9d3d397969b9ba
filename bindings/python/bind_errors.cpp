// Binds types.h and tables.h: Status and handsim::Error as Python exceptions, the enum and def tables. Each exception class also
// derives from the matching builtin, so `except ValueError` catches a bad argument and `except handsim.Error`
// catches anything from handsim; its `status` attribute is the Status it maps.
#include "bindings.h"
#include "convert.h"

#include "handsim/tables.h"
#include "handsim/types.h"

#include <array>

namespace py = pybind11;

namespace handsim {
namespace {

py::object make_exception(py::module_& m, const char* name, py::handle base1, py::handle base2,
                          const char* doc) {
  py::tuple bases = base2 ? py::tuple(py::make_tuple(base1, base2)) : py::tuple(py::make_tuple(base1));
  std::string qualified = std::string("handsim._core.") + name;
  py::object cls = py::reinterpret_steal<py::object>(
      PyErr_NewExceptionWithDoc(qualified.c_str(), doc, bases.ptr(), nullptr));
  if (!cls) throw py::error_already_set();
  m.attr(name) = cls;
  return cls;
}

}  // namespace

void bind_errors(py::module_& m) {
  py_convert::bind_enum<Status>(m, "Status", "What a call returned; the C ABI's status codes.");
  m.def(
      "enum_values",
      [] {
        py::list rows;
        for (const EnumValue& v : kEnumValues) rows.append(py::make_tuple(v.type, v.name, v.value, v.upper, v.constant));
        return rows;
      },
      "Every value of every public enum as (type, C++ name, number, Python name, C constant), from the core's "
      "enum table (handsim/enum_table.h).");
  m.def(
      "def_fields",
      [] {
        py::dict defs;
        for (const DefField& row : kDefFields) {
          py::str def(row.def);
          py::list fields = defs.contains(def) ? py::list(defs[def]) : py::list();
          fields.append(row.field);
          defs[def] = fields;
        }
        for (auto item : defs) defs[item.first] = py::tuple(py::reinterpret_borrow<py::list>(item.second));
        return defs;
      },
      "The fields of every def the bindings mirror, {def: (field, ...)}, from the core's def table "
      "(handsim/def_table.h); handsim.recording saves exactly these.");
  py::object base = make_exception(m, "Error", PyExc_Exception, nullptr, "Base of every handsim error.");
  // Indexed by Status; heap-allocated so the translator (a plain function) can reach them.
  static auto* classes = new std::array<py::object, 6>{
      base,
      make_exception(m, "InvalidArgumentError", base, PyExc_ValueError, "An argument is out of its domain."),
      make_exception(m, "StaleIdError", base, PyExc_LookupError,
                     "An id names a removed object or one of another world."),
      make_exception(m, "InvalidStateError", base, PyExc_RuntimeError, "The call is not allowed now."),
      make_exception(m, "UnsupportedError", base, PyExc_NotImplementedError,
                     "This build lacks the feature (e.g. Ceres)."),
      make_exception(m, "InternalError", base, PyExc_RuntimeError, "An internal invariant broke (a bug)."),
  };
  for (size_t s = 1; s < classes->size(); ++s) (*classes)[s].attr("status") = Status(int(s));
  py::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const Error& e) {
      int s = int(e.status());
      py::object cls = (*classes)[s > 0 && s < 6 ? s : 5];
      PyErr_SetString(cls.ptr(), e.what());
    }
  });
}

}  // namespace handsim
