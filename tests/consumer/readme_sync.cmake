# Script mode (cmake -P), run by the readme_api_in_sync test: the README's main API example must be
# the text that readme_api.cpp builds and runs against the installed package (its includes and its body,
# each between the file's README markers, found verbatim in README.md).
foreach(var README SOURCE)
  if(NOT DEFINED ${var})
    message(FATAL_ERROR "readme_sync.cmake: -D${var}=... is required")
  endif()
endforeach()
file(READ "${README}" readme)
file(READ "${SOURCE}" source)
foreach(part includes body)
  string(FIND "${source}" "// README ${part} begin\n" begin)
  string(FIND "${source}" "// README ${part} end" end)
  if(begin EQUAL -1 OR end EQUAL -1)
    message(FATAL_ERROR "${SOURCE}: no README ${part} markers")
  endif()
  string(LENGTH "// README ${part} begin\n" marker)
  math(EXPR begin "${begin} + ${marker}")
  math(EXPR length "${end} - ${begin}")
  string(SUBSTRING "${source}" ${begin} ${length} text)
  string(REGEX REPLACE "\n[ ]+$" "\n" text "${text}") # the end marker's indentation
  string(FIND "${readme}" "${text}" found)
  if(found EQUAL -1)
    message(FATAL_ERROR "README.md no longer holds the API example's ${part} that ${SOURCE} runs: "
                        "change both together")
  endif()
endforeach()
message(STATUS "readme_api_in_sync: README.md holds readme_api.cpp's example")
