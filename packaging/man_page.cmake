# man_page.cmake: one gzipped man page from a program's --help, with help2man (cmake -P, at build time).
#   -DHELP2MAN=... -DGZIP=... -DPROGRAM=path -DSECTION=1|8 -DNAME="what it is" -DVERSION=x.y.z -DOUT=name.N.gz
#   [-DSUBCOMMANDS=ON]: also a COMMANDS section with each subcommand's --help (the CLI11 "Subcommands:" list).
#   [-DINCLUDE=file.h2m]: help2man sections written by hand (EXIT STATUS, FILES, EXAMPLES: packaging/man/).
# A subcommand's help becomes filled text (an option per .TP paragraph), so the page fits 80 columns.
# gzip -9n: no name or time stamp in the archive, what lintian asks of a man page.
cmake_minimum_required(VERSION 3.25)
get_filename_component(_program_name "${PROGRAM}" NAME)
string(REGEX REPLACE "\\.gz$" "" _page "${OUT}")
set(_include "${_page}.include")
set(_include_option)
# The output folder: Ninja makes it for a command's OUTPUT, the Makefile generator does not (issue 38: a
# page without SUBCOMMANDS that ran first had no folder to write to).
get_filename_component(_folder "${OUT}" DIRECTORY)
file(MAKE_DIRECTORY "${_folder}")

if(SUBCOMMANDS)
  execute_process(COMMAND "${PROGRAM}" --help OUTPUT_VARIABLE _help RESULT_VARIABLE _rc)
  if(NOT _rc EQUAL 0)
    message(FATAL_ERROR "${PROGRAM} --help failed (${_rc})")
  endif()
  string(REGEX REPLACE "^.*\nSubcommands:\n" "" _list "${_help}")
  string(REGEX MATCHALL "(^|\n)  [a-z][a-z0-9-]*" _names "${_list}")
  set(_section "[COMMANDS]\n")
  foreach(_name ${_names})
    string(STRIP "${_name}" _name)
    execute_process(COMMAND "${PROGRAM}" ${_name} --help OUTPUT_VARIABLE _sub RESULT_VARIABLE _rc)
    if(NOT _rc EQUAL 0)
      message(FATAL_ERROR "${PROGRAM} ${_name} --help failed (${_rc})")
    endif()
    # The build path CLI11 prints in "Usage:" becomes the installed name; roff's escape and control
    # characters are quoted so the text shows as printed.
    string(REPLACE "${PROGRAM}" "${_program_name}" _sub "${_sub}")
    string(REPLACE "\\" "\\e" _sub "${_sub}")
    string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" _sub "${_sub}")
    # CLI11's columns as paragraphs: "  NAME  DESCRIPTION" (or DESCRIPTION on the next, indented line) is a
    # .TP with NAME as its tag; a heading ("Usage:", "Options:") starts a paragraph of its own.
    # (\\& before a description: a text line that starts with . or ' is no request.)
    string(REGEX REPLACE "\n  ([^ \n][^\n]*)\n          +([^ \n][^\n]*)" "\n.TP\n\\1\n\\\\&\\2" _sub "\n${_sub}")
    string(REGEX REPLACE "\n  ([^ \n.]+( [^ \n]+)*)  +([^\n]+)" "\n.TP\n\\1\n\\\\&\\3" _sub "${_sub}")
    string(REGEX REPLACE "\n([A-Z][A-Za-z]*:)" "\n.PP\n\\1" _sub "${_sub}")
    string(APPEND _section ".SS ${_name}\n${_sub}\n")
  endforeach()
  file(WRITE "${_include}" "${_section}")
  set(_include_option --include "${_include}")
endif()
if(INCLUDE)
  file(READ "${INCLUDE}" _sections)
  file(APPEND "${_include}" "${_sections}")
  set(_include_option --include "${_include}")
endif()

execute_process(COMMAND "${HELP2MAN}" --no-info --no-discard-stderr --section "${SECTION}" --name "${NAME}"
                        --version-string "${VERSION}" ${_include_option} --output "${_page}" "${PROGRAM}"
                RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "help2man ${PROGRAM} failed (${_rc})")
endif()
file(REMOVE "${_include}" "${OUT}")
execute_process(COMMAND "${GZIP}" -9n "${_page}" RESULT_VARIABLE _rc)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "gzip ${_page} failed (${_rc})")
endif()
