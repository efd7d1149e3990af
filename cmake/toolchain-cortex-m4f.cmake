# CMake toolchain file: Cortex-M4F (ARMv7E-M + FPv4-SP), bare metal, arm-none-eabi-gcc.
#
#   cmake -S . -B build/m4f -DCMAKE_TOOLCHAIN_FILE=cmake/toolchain-cortex-m4f.cmake
#   cmake --build build/m4f
#
# builds libgearsim.a alone: the root CMakeLists.txt turns the host-side
# extras (shared library, examples, tests, benchmark) off when
# CMAKE_CROSSCOMPILING is set.
#
# The FPU is single precision only, so this file turns GEARSIM_SINGLE_PRECISION
# on (gs_real = float; a double build would run every operation through the
# soft-float helpers __aeabi_d*). Set GEARSIM_M4F_ALLOW_DOUBLE=ON to keep
# whatever the cache says instead.
#
# Debian packages: gcc-arm-none-eabi, libnewlib-arm-none-eabi (for linking
# programs; the library itself needs only <stddef.h> and <string.h>).
set(CMAKE_SYSTEM_NAME Generic)
set(CMAKE_SYSTEM_PROCESSOR arm)

set(GEARSIM_M4F_PREFIX "arm-none-eabi-" CACHE STRING "Cross tool prefix")
find_program(CMAKE_C_COMPILER ${GEARSIM_M4F_PREFIX}gcc REQUIRED)
find_program(CMAKE_AR ${GEARSIM_M4F_PREFIX}ar REQUIRED)
find_program(CMAKE_RANLIB ${GEARSIM_M4F_PREFIX}ranlib REQUIRED)
find_program(CMAKE_OBJCOPY ${GEARSIM_M4F_PREFIX}objcopy)
find_program(CMAKE_SIZE ${GEARSIM_M4F_PREFIX}size)
find_program(CMAKE_NM ${GEARSIM_M4F_PREFIX}nm)

# try_compile links a static library instead of an executable: there is no
# startup code or linker script at configure time.
set(CMAKE_TRY_COMPILE_TARGET_TYPE STATIC_LIBRARY)

# -ffunction-sections/-fdata-sections let the application's --gc-sections drop
# whatever it does not call (e.g. the Simple Gear when only the rack is used).
set(GEARSIM_M4F_FLAGS "-mcpu=cortex-m4 -mthumb -mfpu=fpv4-sp-d16 -mfloat-abi=hard -ffunction-sections -fdata-sections")
set(CMAKE_C_FLAGS_INIT "${GEARSIM_M4F_FLAGS}")
set(CMAKE_ASM_FLAGS_INIT "${GEARSIM_M4F_FLAGS}")
# CMake ignores *_INIT when CMAKE_C_FLAGS is given on the command line, which
# would silently build ARM-mode soft-float code: prepend the target flags to
# such a value instead (CMAKE_C_FLAGS is also on the link line, so newlib's
# thumb/v7e-m+fp/hard multilib is selected).
if(DEFINED CACHE{CMAKE_C_FLAGS} AND NOT "$CACHE{CMAKE_C_FLAGS}" MATCHES "-mcpu=")
  set(CMAKE_C_FLAGS "${GEARSIM_M4F_FLAGS} $CACHE{CMAKE_C_FLAGS}")
endif()
set(CMAKE_EXE_LINKER_FLAGS_INIT "-Wl,--gc-sections")

if(NOT GEARSIM_M4F_ALLOW_DOUBLE)
  set(GEARSIM_SINGLE_PRECISION ON CACHE BOOL "gs_real is float (Cortex-M4F: single-precision FPU)" FORCE)
endif()
# No shared libraries on bare metal.
set(GEARSIM_BUILD_SHARED OFF CACHE BOOL "Build the shared library too" FORCE)

set(CMAKE_FIND_ROOT_PATH_MODE_PROGRAM NEVER)
set(CMAKE_FIND_ROOT_PATH_MODE_LIBRARY ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_INCLUDE ONLY)
set(CMAKE_FIND_ROOT_PATH_MODE_PACKAGE ONLY)
