# Warnings for the project's own targets only (never forced on consumers).
function(ssta_set_warnings target)
  target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wno-unused-parameter)
endfunction()
