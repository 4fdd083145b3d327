# cmake -DAPP=<exe> -DNAME=<app> -DHELP2MAN=<help2man> -DOUT=<page.1> -DVERSION=<v> -P geohaz_man_page.cmake
# A man page from `APP --help` and `APP --version` (help2man), with `APP --help-config` (every config
# key with unit, default and range), when the app has it, as a CONFIGURATION section.
# help2man and the app run in a UTF-8 locale: in the default C locale help2man writes every
# non-ASCII character of the help text (m³, θ, °) as "?" (issue #29).
set(ENV{LC_ALL} C.UTF-8)
get_filename_component(_dir ${OUT} DIRECTORY)
file(MAKE_DIRECTORY ${_dir})
set(_include ${OUT}.include)
set(_text "[SEE ALSO]\nThe documentation in @GEOHAZ_DATADIR@ (README.md, docs/) and the example cases in @GEOHAZ_DATADIR@/data.\n")
execute_process(COMMAND ${APP} --help-config OUTPUT_VARIABLE _cfg RESULT_VARIABLE _rc ERROR_QUIET)
if(_rc EQUAL 0 AND _cfg)
  # roff: backslashes doubled, no line may start with a control character; kept as preformatted text.
  string(REPLACE "\\" "\\\\" _cfg "${_cfg}")
  string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" _cfg "${_cfg}")
  string(APPEND _text "[CONFIGURATION]\nEvery key of the TOML configuration (--config FILE, --set key=value), with its unit, default and allowed range:\n.PP\n.nf\n${_cfg}.fi\n")
endif()
file(WRITE ${_include} "${_text}")
# NAME: "app - <what the first line of --help says after 'app version: '>".
execute_process(COMMAND ${APP} --help OUTPUT_VARIABLE _help ERROR_QUIET)
string(REGEX MATCH "^[^\n]*" _first "${_help}")
string(REGEX REPLACE "^[^:]*: *" "" _name "${_first}")
string(REGEX REPLACE "\\.$" "" _name "${_name}")
execute_process(
  COMMAND ${HELP2MAN} --no-info --locale=C.UTF-8 "--name=${_name}" --no-discard-stderr --section=1 --source=geohaz --version-string=${VERSION}
          --include=${_include} --output=${OUT} ${APP}
  RESULT_VARIABLE _rc ERROR_VARIABLE _err)
if(NOT _rc EQUAL 0)
  message(FATAL_ERROR "help2man failed for ${NAME}: ${_err}")
endif()
