# SPDX-License-Identifier: MIT
# Finding Debian 12's ParaView 5.11 for the plugin (docs/PARAVIEW.md, "Building").
#
# paraview-dev's CMake files import the Python modules of python3-paraview and stop when those
# files are missing; python3-paraview conflicts with python3-vtk9, which the tests use (installing
# it removes python3-vtk9 and mayavi2). scripts/install-deps.sh --tests therefore unpacks
# python3-paraview's files into UVR_PARAVIEW_PYTHON_PREFIX without installing the package. Where
# the package itself is not installed, ParaView is found through a prefix of symbolic links in
# the build folder: /usr's include, lib and share folders and programs, and lib/python3 from the
# unpacked files. Nothing outside the build folder changes.
#
# Sets UVR_PARAVIEW_FOUND and UVR_PARAVIEW_PYTHONPATH (what pvbatch needs on PYTHONPATH; empty
# when the package is installed).
set(UVR_PARAVIEW_PYTHON_PREFIX "/opt/uvr/python3-paraview" CACHE PATH
    "Where scripts/install-deps.sh --tests unpacked python3-paraview's files")
set(UVR_PARAVIEW_FOUND OFF)
set(UVR_PARAVIEW_PYTHONPATH "")
set(_uvr_pv_config_dir "/usr/lib/x86_64-linux-gnu/cmake/paraview-5.11")
set(_uvr_pv_python "lib/python3/dist-packages")
if(DEFINED ParaView_DIR AND NOT ParaView_DIR MATCHES "NOTFOUND$" AND
   NOT ParaView_DIR MATCHES "^${_uvr_pv_config_dir}|/paraview-prefix/")
    # Given by hand (another ParaView build): found as it says.
    find_package(ParaView 5.11 QUIET COMPONENTS RemotingViews)
    set(UVR_PARAVIEW_FOUND ${ParaView_FOUND})
elseif(EXISTS "${_uvr_pv_config_dir}/paraview-config.cmake")
    if(EXISTS "/usr/${_uvr_pv_python}/paraview/modules")
        find_package(ParaView 5.11 QUIET COMPONENTS RemotingViews PATHS "${_uvr_pv_config_dir}"
                     NO_DEFAULT_PATH)
        set(UVR_PARAVIEW_FOUND ${ParaView_FOUND})
    elseif(EXISTS "${UVR_PARAVIEW_PYTHON_PREFIX}/usr/${_uvr_pv_python}/paraview/modules")
        set(_farm "${CMAKE_BINARY_DIR}/paraview-prefix")
        file(MAKE_DIRECTORY "${_farm}/lib" "${_farm}/bin")
        foreach(_d include share)
            file(CREATE_LINK "/usr/${_d}" "${_farm}/${_d}" SYMBOLIC)
        endforeach()
        # The CMake files are copied, not linked: loaded through a link to their own folder
        # they take /usr as their prefix again. The libraries they import are linked.
        set(_lib "${_farm}/lib/x86_64-linux-gnu")
        file(MAKE_DIRECTORY "${_lib}/cmake")
        file(COPY "${_uvr_pv_config_dir}" DESTINATION "${_lib}/cmake")
        file(GLOB _entries RELATIVE /usr/lib/x86_64-linux-gnu /usr/lib/x86_64-linux-gnu/libvtk*
             /usr/lib/x86_64-linux-gnu/libpq* /usr/lib/x86_64-linux-gnu/paraview-5.11)
        foreach(_e ${_entries})
            file(CREATE_LINK "/usr/lib/x86_64-linux-gnu/${_e}" "${_lib}/${_e}" SYMBOLIC)
        endforeach()
        # The wrappers' class hierarchies of ParaView's modules ship with python3-paraview.
        file(MAKE_DIRECTORY "${_lib}/vtk/hierarchy")
        file(CREATE_LINK
             "${UVR_PARAVIEW_PYTHON_PREFIX}/usr/lib/x86_64-linux-gnu/vtk/hierarchy/ParaView"
             "${_lib}/vtk/hierarchy/ParaView" SYMBOLIC)
        file(CREATE_LINK "${UVR_PARAVIEW_PYTHON_PREFIX}/usr/lib/python3" "${_farm}/lib/python3"
             SYMBOLIC)
        # The programs the CMake files import: Debian's, and pvpython from the unpacked files.
        file(GLOB _uvr_pv_targets "${_uvr_pv_config_dir}/*targets*.cmake"
             "${_uvr_pv_config_dir}/vtk/*targets*.cmake")
        set(_programs "")
        foreach(_f ${_uvr_pv_targets})
            file(STRINGS "${_f}" _lines REGEX "_IMPORT_PREFIX}/bin/")
            foreach(_l ${_lines})
                string(REGEX MATCHALL "_IMPORT_PREFIX}/bin/[^\" ]+" _m "${_l}")
                list(APPEND _programs ${_m})
            endforeach()
        endforeach()
        list(REMOVE_DUPLICATES _programs)
        foreach(_p ${_programs})
            string(REGEX REPLACE ".*/bin/" "" _p "${_p}")
            if(EXISTS "/usr/bin/${_p}")
                file(CREATE_LINK "/usr/bin/${_p}" "${_farm}/bin/${_p}" SYMBOLIC)
            else()
                file(CREATE_LINK "${UVR_PARAVIEW_PYTHON_PREFIX}/usr/bin/${_p}"
                     "${_farm}/bin/${_p}" SYMBOLIC)
            endif()
        endforeach()
        # ParaView's config finds its VTK at VTK_DIR when that is set (by an earlier run).
        set(_dir "${_farm}/lib/x86_64-linux-gnu/cmake/paraview-5.11")
        set(ParaView_DIR "${_dir}" CACHE PATH "ParaView's CMake files" FORCE)
        set(VTK_DIR "${_dir}/vtk" CACHE PATH "ParaView's VTK's CMake files" FORCE)
        find_package(ParaView 5.11 QUIET COMPONENTS RemotingViews PATHS "${_dir}"
                     NO_DEFAULT_PATH)
        set(UVR_PARAVIEW_FOUND ${ParaView_FOUND})
        set(UVR_PARAVIEW_PYTHONPATH "${UVR_PARAVIEW_PYTHON_PREFIX}/usr/${_uvr_pv_python}")
    else()
        message(STATUS "uvr: paraview-dev is installed but not python3-paraview's files, which "
                       "its CMake files import (scripts/install-deps.sh --tests unpacks them)")
    endif()
endif()
