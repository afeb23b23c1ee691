# toposlam_install_unit(TARGET t UNIT file DIR sbin|bin DOC page.md): installs the systemd unit `file` of the
# program `t` into <prefix>/lib/systemd/system, where systemd looks for units of packages. The unit names
# /usr/local/<DIR>/<t> and /usr/local/share/doc/toposlam/<DOC>; the installed copy names the install
# prefix's instead, rewritten at install time (cmake --install --prefix decides it then). A second copy, in
# <binary dir>/verify/, names the build tree's binary: the tests run `systemd-analyze verify` on it.
function(toposlam_install_unit)
  cmake_parse_arguments(ARG "" "TARGET;UNIT;DIR;DOC" "" ${ARGN})
  get_filename_component(_name "${ARG_UNIT}" NAME)
  if(ARG_DIR STREQUAL "sbin")
    set(_dir "${CMAKE_INSTALL_SBINDIR}")
    set(_full_dir "${CMAKE_INSTALL_FULL_SBINDIR}")
  else()
    set(_dir "${CMAKE_INSTALL_BINDIR}")
    set(_full_dir "${CMAKE_INSTALL_FULL_BINDIR}")
  endif()
  file(READ "${ARG_UNIT}" _unit)
  string(REPLACE "/usr/local/${ARG_DIR}/${ARG_TARGET}" "${_full_dir}/${ARG_TARGET}" _installed "${_unit}")
  string(REPLACE "/usr/local/share/doc/toposlam" "${CMAKE_INSTALL_FULL_DOCDIR}" _installed "${_installed}")
  file(GENERATE OUTPUT "${CMAKE_CURRENT_BINARY_DIR}/install/${_name}" CONTENT "${_installed}")
  string(REPLACE "/usr/local/${ARG_DIR}/${ARG_TARGET}" "$<TARGET_FILE:${ARG_TARGET}>" _build "${_unit}")
  file(GENERATE OUTPUT "${CMAKE_CURRENT_BINARY_DIR}/verify/${_name}" CONTENT "${_build}")
  set_property(DIRECTORY APPEND PROPERTY CMAKE_CONFIGURE_DEPENDS "${ARG_UNIT}")
  install(FILES "${CMAKE_CURRENT_BINARY_DIR}/install/${_name}" DESTINATION lib/systemd/system)
  install(CODE "
    set(_unit \"\$ENV{DESTDIR}\${CMAKE_INSTALL_PREFIX}/lib/systemd/system/${_name}\")
    file(READ \"\${_unit}\" _text)
    string(REGEX REPLACE \"ExecStart=[^\n]*\" \"ExecStart=\${CMAKE_INSTALL_PREFIX}/${_dir}/${ARG_TARGET}\" _text \"\${_text}\")
    string(REGEX REPLACE \"Documentation=file://[^\n]*/${ARG_DOC}\"
           \"Documentation=file://\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_DOCDIR}/${ARG_DOC}\" _text \"\${_text}\")
    file(WRITE \"\${_unit}\" \"\${_text}\")
  ")
endfunction()
