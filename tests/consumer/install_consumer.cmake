# Registers the `install_consumer` test (included from tests/CMakeLists.txt): install this build into a
# scratch prefix inside the build tree, configure and build tests/consumer against it with
# find_package(mrtile), and run its programs. It proves that the installed headers, targets and
# dependency lookups are complete, which no in-tree test can.

# More programs to build and run against the installed package, one executable per file (named after
# the file), e.g. the README's example: list(APPEND MRTILE_CONSUMER_EXTRA_SOURCES <absolute path>).
set(MRTILE_CONSUMER_EXTRA_SOURCES "")
list(APPEND MRTILE_CONSUMER_EXTRA_SOURCES ${CMAKE_CURRENT_LIST_DIR}/readme_example.cpp
     ${CMAKE_CURRENT_LIST_DIR}/readme_api.cpp)

string(REPLACE ";" "|" _mrtile_consumer_extra "${MRTILE_CONSUMER_EXTRA_SOURCES}")
set(_mrtile_consumer_flags "")
if(MRTILE_SANITIZE)
  set(_mrtile_consumer_flags "-fsanitize=address,undefined")
endif()
add_test(NAME install_consumer
         COMMAND ${CMAKE_COMMAND}
                 -DBUILD_DIR=${PROJECT_BINARY_DIR}
                 -DWORK_DIR=${PROJECT_BINARY_DIR}/install_consumer
                 -DCONSUMER_DIR=${CMAKE_CURRENT_LIST_DIR}
                 -DEXTRA_SOURCES=${_mrtile_consumer_extra}
                 -DGENERATOR=${CMAKE_GENERATOR}
                 -DCXX_COMPILER=${CMAKE_CXX_COMPILER}
                 -DBUILD_TYPE=${CMAKE_BUILD_TYPE}
                 -DWERROR=${MRTILE_WERROR}
                 -DEXTRA_FLAGS=${_mrtile_consumer_flags}
                 -P ${CMAKE_CURRENT_LIST_DIR}/run_consumer.cmake)
set_tests_properties(install_consumer PROPERTIES TIMEOUT 900)

# readme_api.cpp runs the README's main API example; this keeps the two the same text (QA round 64: the
# example was true but unguarded).
add_test(NAME readme_api_in_sync
         COMMAND ${CMAKE_COMMAND} -DREADME=${PROJECT_SOURCE_DIR}/README.md
                 -DSOURCE=${CMAKE_CURRENT_LIST_DIR}/readme_api.cpp -P ${CMAKE_CURRENT_LIST_DIR}/readme_sync.cmake)
# readme_example.cpp runs the README's local-refinement examples (QA round 71: they had drifted from it).
add_test(NAME readme_example_in_sync
         COMMAND ${CMAKE_COMMAND} -DREADME=${PROJECT_SOURCE_DIR}/README.md
                 -DSOURCE=${CMAKE_CURRENT_LIST_DIR}/readme_example.cpp -DPARTS=focus,incremental
                 -P ${CMAKE_CURRENT_LIST_DIR}/readme_sync.cmake)
