# TOPOSLAM_SANITIZE=address,undefined or thread builds every target with those sanitizers.
if(TOPOSLAM_SANITIZE)
  set(_flags -fsanitize=${TOPOSLAM_SANITIZE} -fno-omit-frame-pointer -fno-sanitize-recover=all)
  add_compile_options(${_flags})
  add_link_options(-fsanitize=${TOPOSLAM_SANITIZE})
  message(STATUS "toposlam: building with sanitizers: ${TOPOSLAM_SANITIZE}")
endif()
