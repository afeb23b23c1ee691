# The rooms' rules of docs/architecture.md ("Rooms: folders and what may include what"), checked on the
# target graph at configure time: each listed library may reach (directly or through others) only the
# project libraries allowed here. A forbidden edge is a configure error naming the path, so a link that
# breaks the layering fails before anything is built. Third-party libraries are not checked.

# Project libraries (toposlam_*) that `target` links, directly and through other project libraries.
function(toposlam_project_deps target out)
  set(seen "")
  set(todo ${target})
  while(todo)
    list(POP_FRONT todo current)
    if(NOT TARGET ${current})
      continue()
    endif()
    # PUBLIC and PRIVATE links (LINK_LIBRARIES) and what an INTERFACE library passes on.
    set(links "")
    get_target_property(type ${current} TYPE)
    if(NOT type STREQUAL "INTERFACE_LIBRARY")
      get_target_property(own ${current} LINK_LIBRARIES)
      if(own)
        list(APPEND links ${own})
      endif()
    endif()
    get_target_property(passed ${current} INTERFACE_LINK_LIBRARIES)
    if(passed)
      list(APPEND links ${passed})
    endif()
    foreach(link IN LISTS links)
      if(link MATCHES "^toposlam_" AND NOT link IN_LIST seen)
        list(APPEND seen ${link})
        list(APPEND todo ${link})
      endif()
    endforeach()
  endwhile()
  set(${out} ${seen} PARENT_SCOPE)
endfunction()

# toposlam_check_layering(): a FATAL_ERROR for the first library that reaches one it may not.
function(toposlam_check_layering)
  set(allowed_toposlam_core "")
  set(allowed_toposlam_fingerprint toposlam_core)
  set(allowed_toposlam_matching toposlam_fingerprint toposlam_core)
  set(allowed_toposlam_segmentation toposlam_fingerprint toposlam_core)
  set(allowed_toposlam_topology toposlam_fingerprint toposlam_core)
  set(allowed_toposlam_run_folder toposlam_segmentation toposlam_fingerprint toposlam_core toposlam_os)
  foreach(target toposlam_core toposlam_fingerprint toposlam_matching toposlam_segmentation toposlam_topology
                 toposlam_run_folder)
    if(NOT TARGET ${target})
      message(FATAL_ERROR "layering check: ${target} is not a target (cmake/ToposlamLayering.cmake lists it)")
    endif()
    toposlam_project_deps(${target} reached)
    foreach(dep IN LISTS reached)
      if(NOT dep IN_LIST allowed_${target})
        message(FATAL_ERROR "layering check: ${target} links ${dep} (directly or through another library); "
                            "it may reach only: ${allowed_${target}} (docs/architecture.md, Rooms)")
      endif()
    endforeach()
  endforeach()
endfunction()
