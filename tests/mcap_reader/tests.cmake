# `ssta export --format mcap` read by an independent reader: Foxglove's npm packages at the
# versions of package-lock.json, installed into <build>/mcap_reader by `npm ci` at build time
# (again only when package.json or package-lock.json change); node and npm come from
# scripts/install-deps.sh.
find_program(SSTA_NODE node)
find_program(SSTA_NPM npm)
if(NOT SSTA_NODE OR NOT SSTA_NPM)
  message(FATAL_ERROR "node and npm not found (the MCAP reader test needs them): run scripts/install-deps.sh")
endif()
set(SSTA_MCAP_READER_DIR ${PROJECT_BINARY_DIR}/mcap_reader)
add_custom_command(
  OUTPUT ${SSTA_MCAP_READER_DIR}/node_modules/.package-lock.json
  COMMAND ${CMAKE_COMMAND} -E make_directory ${SSTA_MCAP_READER_DIR}
  COMMAND ${CMAKE_COMMAND} -E copy ${CMAKE_CURRENT_LIST_DIR}/package.json ${CMAKE_CURRENT_LIST_DIR}/package-lock.json
          ${SSTA_MCAP_READER_DIR}
  COMMAND ${SSTA_NPM} ci --prefix ${SSTA_MCAP_READER_DIR} --no-audit --no-fund --loglevel=error
  DEPENDS ${CMAKE_CURRENT_LIST_DIR}/package.json ${CMAKE_CURRENT_LIST_DIR}/package-lock.json
  COMMENT "npm ci: the independent MCAP reader's packages")
add_custom_target(ssta_mcap_reader ALL DEPENDS ${SSTA_MCAP_READER_DIR}/node_modules/.package-lock.json)

add_test(NAME mcap_reader.NodeReaderDecodesTheExportAsTheGridShowsIt
         COMMAND bash ${CMAKE_CURRENT_LIST_DIR}/mcap_reader_test.sh $<TARGET_FILE:ssta_cli> ${PROJECT_SOURCE_DIR}
                 ${SSTA_MCAP_READER_DIR})
set_tests_properties(mcap_reader.NodeReaderDecodesTheExportAsTheGridShowsIt PROPERTIES TIMEOUT 120
                     FIXTURES_REQUIRED litter ENVIRONMENT TMPDIR=${SSTA_TEST_TMPDIR})
