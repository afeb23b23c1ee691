# toposlam_install_config(FILE...): installs config files into <sysconfdir>/toposlam, where toposlamd and the
# unit's ConfigurationDirectory= look. GNUInstallDirs' rule for sysconfdir (/usr -> /etc, /opt/X -> /etc/opt/X,
# any other prefix P -> P/etc) applied to the prefix given at *install* time, so
# `cmake --install build --prefix /usr` puts them in /etc/toposlam/, not /usr/etc/toposlam/ (GNUInstallDirs
# alone decides at configure time). An absolute -DCMAKE_INSTALL_SYSCONFDIR=DIR is used as it is.
# file(INSTALL) honours DESTDIR and records the files in install_manifest.txt.
function(toposlam_install_config)
  if(IS_ABSOLUTE "${CMAKE_INSTALL_SYSCONFDIR}")
    install(FILES ${ARGN} DESTINATION ${CMAKE_INSTALL_SYSCONFDIR}/toposlam)
    return()
  endif()
  set(_files)
  foreach(f ${ARGN})
    get_filename_component(f "${f}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    string(APPEND _files " \"${f}\"")
  endforeach()
  install(CODE "
    if(CMAKE_INSTALL_PREFIX MATCHES \"^/usr/*$\")
      set(_toposlam_sysconfdir \"/${CMAKE_INSTALL_SYSCONFDIR}\")
    elseif(CMAKE_INSTALL_PREFIX MATCHES \"^/opt/(.+)$\")
      set(_toposlam_sysconfdir \"/${CMAKE_INSTALL_SYSCONFDIR}/opt/\${CMAKE_MATCH_1}\")
    else()
      set(_toposlam_sysconfdir \"\${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_SYSCONFDIR}\")
    endif()
    file(INSTALL DESTINATION \"\${_toposlam_sysconfdir}/toposlam\" TYPE FILE FILES${_files})
  ")
endfunction()
