# Finds what the Python API (python/) needs: a Python 3 interpreter with its headers, NumPy and
# pybind11. Sets SSTA_PYTHON_FOUND, and on success Python3_EXECUTABLE and the pybind11 targets.
#
# The interpreter must be one that has NumPy: the first python3 on PATH is often a pyenv or conda
# one without it while Debian's /usr/bin/python3 has python3-numpy. So each candidate is asked to
# import it, in order: a Python3_EXECUTABLE given on the command line, the python3 on PATH,
# /usr/bin/python3.

set(SSTA_PYTHON_FOUND OFF)
set(_ssta_python_candidates "")
if(Python3_EXECUTABLE)
  list(APPEND _ssta_python_candidates "${Python3_EXECUTABLE}")
else()
  find_program(_ssta_path_python3 NAMES python3 NO_CACHE)
  if(_ssta_path_python3)
    list(APPEND _ssta_python_candidates "${_ssta_path_python3}")
  endif()
  if(EXISTS /usr/bin/python3)
    list(APPEND _ssta_python_candidates /usr/bin/python3)
  endif()
endif()

set(_ssta_python "")
foreach(candidate IN LISTS _ssta_python_candidates)
  execute_process(COMMAND "${candidate}" -c "import numpy" RESULT_VARIABLE _ssta_rc OUTPUT_QUIET ERROR_QUIET)
  if(_ssta_rc EQUAL 0)
    set(_ssta_python "${candidate}")
    break()
  endif()
endforeach()
# pybind11's CMake files: pybind11-dev puts them on CMake's default path, python3-pybind11 (or a
# pip install) beside the Python package, which tells where.
set(_ssta_pybind11_dir "")
if(_ssta_python)
  execute_process(COMMAND "${_ssta_python}" -c "import pybind11; print(pybind11.get_cmake_dir(), end='')"
                  OUTPUT_VARIABLE _ssta_pybind11_dir ERROR_QUIET)
endif()

if(_ssta_python)
  set(Python3_EXECUTABLE "${_ssta_python}" CACHE FILEPATH "Python the ssta module is built for" FORCE)
  # Development.Module: an extension module does not link libpython.
  find_package(Python3 COMPONENTS Interpreter Development.Module NumPy QUIET)
  if(Python3_FOUND AND Python3_NumPy_FOUND)
    # With Python3 found first, pybind11 builds the module for that interpreter (FindPython mode).
    find_package(pybind11 2.6 CONFIG QUIET HINTS "${_ssta_pybind11_dir}")
    if(pybind11_FOUND)
      set(SSTA_PYTHON_FOUND ON)
    endif()
  endif()
endif()

if(SSTA_PYTHON_FOUND)
  message(STATUS "Python API: ${Python3_EXECUTABLE} (Python ${Python3_VERSION}, NumPy ${Python3_NumPy_VERSION}, pybind11 ${pybind11_VERSION})")
else()
  message(STATUS "Python API: off (needs python3-dev, python3-numpy and pybind11-dev / python3-pybind11)")
endif()
