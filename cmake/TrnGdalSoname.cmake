# SPDX-License-Identifier: Apache-2.0
# cmake/TrnGdalSoname.cmake - trn_gdal_soname(<var>): the soname of the libgdal
# CMake finds (libgdal.so.32 for Debian 12's GDAL 3.6), or "" when there is
# none. tools/trn/gdal_dl.c tries it first when it loads GDAL at run time
# (TRN_GDAL_SONAME); without it the loader tries the usual names.
function(trn_gdal_soname out)
  set(_so "")
  find_package(GDAL QUIET)
  if(GDAL_FOUND)
    set(_lib "${GDAL_LIBRARY}")
    if(NOT _lib AND TARGET GDAL::GDAL)
      get_target_property(_lib GDAL::GDAL IMPORTED_LOCATION)
    endif()
    if(_lib AND EXISTS "${_lib}")
      file(REAL_PATH "${_lib}" _real)
      get_filename_component(_name "${_real}" NAME)
      if(_name MATCHES "^(libgdal\\.so\\.[0-9]+)")
        set(_so "${CMAKE_MATCH_1}")
      endif()
    endif()
  endif()
  set(${out} "${_so}" PARENT_SCOPE)
endfunction()
