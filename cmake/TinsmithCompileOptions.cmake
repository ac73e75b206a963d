# Compile options shared by every tinsmith target: an interface target that each
# library, tool and test links. -ffp-contract=off keeps floating-point results
# (and so golden files) identical across optimisation levels and machines.
add_library(tinsmith_options INTERFACE)
add_library(tinsmith::options ALIAS tinsmith_options)

target_compile_options(tinsmith_options INTERFACE
  -Wall -Wextra -Wpedantic -ffp-contract=off
  $<$<CONFIG:Release>:-O2>)
if(TINSMITH_WERROR)
  target_compile_options(tinsmith_options INTERFACE -Werror)
endif()
if(TINSMITH_SANITIZE)
  target_compile_options(tinsmith_options INTERFACE
    -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  target_link_options(tinsmith_options INTERFACE -fsanitize=address,undefined)
endif()
# Release keeps assertions out; -O2 rather than CMake's default -O3.
set(CMAKE_CXX_FLAGS_RELEASE "-O2 -DNDEBUG" CACHE STRING "" FORCE)
