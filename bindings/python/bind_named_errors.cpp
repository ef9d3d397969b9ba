// The call wrapper of handsim.argument_errors in C: `_core._name_errors(function, handler)` is a callable that passes
// its arguments straight on to the pybind11 `function` (vectorcall, no tuple or dict built) and, only when that
// raises TypeError, calls `handler(error, args, kwargs)`, which names the refused argument or re-raises. A Python
// wrapper function cost every successful call of every bound function its own frame, *args/**kwargs packing and a
// try block: 1.5k instructions a World.step (docs/performance.md "Session 16"), more than the input check.
// It binds like a method (a method descriptor: `world.step(...)` calls it with the world first, no bound method
// made), so one type serves module functions, methods, static methods, constructors and property setters; its
// instance dict takes functools.update_wrapper's attributes (__name__, __doc__, __wrapped__, __wrapped_core__).
#include "bindings.h"

#include <structmember.h>

#include <cstddef>

namespace py = pybind11;

namespace handsim {
namespace {

struct NamedErrors {
  PyObject_HEAD
  PyObject* function;  // the pybind11 callable
  PyObject* handler;   // handler(error, args tuple, kwargs dict): raises
  PyObject* dict;      // the instance dict
  vectorcallfunc vectorcall;
};

// On TypeError: the handler sees the error and the call as Python would have packed it.
PyObject* refused(NamedErrors* w, PyObject* const* args, size_t nargsf, PyObject* kwnames) {
  PyObject *type, *value, *traceback;
  PyErr_Fetch(&type, &value, &traceback);
  PyErr_NormalizeException(&type, &value, &traceback);
  if (traceback) PyException_SetTraceback(value, traceback);
  const Py_ssize_t n = PyVectorcall_NARGS(nargsf), nk = kwnames ? PyTuple_GET_SIZE(kwnames) : 0;
  PyObject* positional = PyTuple_New(n);
  PyObject* keywords = PyDict_New();
  PyObject* result = nullptr;
  if (positional && keywords) {
    for (Py_ssize_t i = 0; i < n; ++i) {
      Py_INCREF(args[i]);
      PyTuple_SET_ITEM(positional, i, args[i]);
    }
    bool ok = true;
    for (Py_ssize_t k = 0; k < nk && ok; ++k) ok = PyDict_SetItem(keywords, PyTuple_GET_ITEM(kwnames, k), args[n + k]) == 0;
    if (ok) result = PyObject_CallFunctionObjArgs(w->handler, value, positional, keywords, nullptr);
  }
  Py_XDECREF(positional);
  Py_XDECREF(keywords);
  Py_XDECREF(type);
  Py_XDECREF(value);
  Py_XDECREF(traceback);
  return result;
}

PyObject* named_call(PyObject* self, PyObject* const* args, size_t nargsf, PyObject* kwnames) {
  auto* w = reinterpret_cast<NamedErrors*>(self);
  PyObject* result = PyObject_Vectorcall(w->function, args, nargsf, kwnames);
  if (result || !PyErr_ExceptionMatches(PyExc_TypeError)) return result;
  return refused(w, args, nargsf, kwnames);
}

// As a class attribute: unbound on the class, bound to the instance (like a function).
PyObject* named_get(PyObject* self, PyObject* instance, PyObject*) {
  if (instance == nullptr || instance == Py_None) {
    Py_INCREF(self);
    return self;
  }
  return PyMethod_New(self, instance);
}

int named_traverse(PyObject* self, visitproc visit, void* arg) {
  auto* w = reinterpret_cast<NamedErrors*>(self);
  Py_VISIT(w->function);
  Py_VISIT(w->handler);
  Py_VISIT(w->dict);
  return 0;
}

int named_clear(PyObject* self) {
  auto* w = reinterpret_cast<NamedErrors*>(self);
  Py_CLEAR(w->function);
  Py_CLEAR(w->handler);
  Py_CLEAR(w->dict);
  return 0;
}

void named_dealloc(PyObject* self) {
  PyTypeObject* type = Py_TYPE(self);
  PyObject_GC_UnTrack(self);
  named_clear(self);
  type->tp_free(self);
  Py_DECREF(type);
}

PyMemberDef named_members[] = {
    {"__vectorcalloffset__", T_PYSSIZET, offsetof(NamedErrors, vectorcall), READONLY, nullptr},
    {"__dictoffset__", T_PYSSIZET, offsetof(NamedErrors, dict), READONLY, nullptr},
    {nullptr, 0, 0, 0, nullptr}};

PyGetSetDef named_getset[] = {{"__dict__", PyObject_GenericGetDict, PyObject_GenericSetDict, nullptr, nullptr},
                               {nullptr, nullptr, nullptr, nullptr, nullptr}};

PyType_Slot named_slots[] = {{Py_tp_call, reinterpret_cast<void*>(PyVectorcall_Call)},
                             {Py_tp_descr_get, reinterpret_cast<void*>(named_get)},
                             {Py_tp_traverse, reinterpret_cast<void*>(named_traverse)},
                             {Py_tp_clear, reinterpret_cast<void*>(named_clear)},
                             {Py_tp_dealloc, reinterpret_cast<void*>(named_dealloc)},
                             {Py_tp_members, named_members},
                             {Py_tp_getset, named_getset},
                             {0, nullptr}};

PyType_Spec named_spec = {"handsim._core.named_errors", sizeof(NamedErrors), 0,
                          Py_TPFLAGS_DEFAULT | Py_TPFLAGS_HAVE_GC | Py_TPFLAGS_HAVE_VECTORCALL |
                              Py_TPFLAGS_METHOD_DESCRIPTOR,
                          named_slots};

}  // namespace

void bind_named_errors(py::module_& m) {
  auto type = py::reinterpret_steal<py::object>(PyType_FromSpec(&named_spec));
  if (!type) throw py::error_already_set();
  m.def(
      "_name_errors",
      [type](py::object function, py::object handler) {
        auto* cls = reinterpret_cast<PyTypeObject*>(type.ptr());
        auto* w = reinterpret_cast<NamedErrors*>(cls->tp_alloc(cls, 0));
        if (!w) throw py::error_already_set();
        w->function = function.release().ptr();
        w->handler = handler.release().ptr();
        w->dict = PyDict_New();
        w->vectorcall = named_call;
        return py::reinterpret_steal<py::object>(reinterpret_cast<PyObject*>(w));
      },
      py::arg("function"), py::arg("handler"),
      "A callable that calls `function` with its arguments and, when that raises TypeError, calls\n"
      "handler(error, args, kwargs) (handsim.argument_errors: names the refused argument, or re-raises).");
}

}  // namespace handsim
