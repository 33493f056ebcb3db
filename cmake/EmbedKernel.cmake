# SPDX-License-Identifier: BSD-3-Clause
# Flattens a kernel source and its quoted #includes into one string and writes it as a C++ source
# defining `extern const char* const raymap::kernels::<SYMBOL>`.
#   cmake -DROOT=<repo> -DINPUT=<path below ROOT> -DOUTPUT=<file.cpp> -DSYMBOL=<name> -P EmbedKernel.cmake
# Includes resolve against the including file's folder, then ROOT; each file is inlined once
# (the headers carry include guards anyway). Nothing but this file is needed at run time.
cmake_minimum_required(VERSION 3.25)

set(raymap_embedded_files "")

# The file is handled as one string (never as a CMake list: kernel code holds ';' and '[').
function(raymap_flatten path out_var)
  get_filename_component(dir "${path}" DIRECTORY)
  file(READ "${path}" content)
  string(REGEX MATCHALL "#[ \t]*include[ \t]+\"[^\"]+\"" directives "${content}")
  foreach(directive IN LISTS directives)
    string(REGEX REPLACE "^#[ \t]*include[ \t]+\"([^\"]+)\"$" "\\1" name "${directive}")
    if(EXISTS "${dir}/${name}")
      get_filename_component(target "${dir}/${name}" ABSOLUTE)
    elseif(EXISTS "${ROOT}/${name}")
      get_filename_component(target "${ROOT}/${name}" ABSOLUTE)
    else()
      message(FATAL_ERROR "${path}: cannot find included file \"${name}\"")
    endif()
    set(inner "")
    if(NOT target IN_LIST raymap_embedded_files)
      list(APPEND raymap_embedded_files "${target}")
      raymap_flatten("${target}" inner)
    endif()
    string(REPLACE "${directive}" "${inner}" content "${content}")
  endforeach()
  set(${out_var} "${content}" PARENT_SCOPE)
  set(raymap_embedded_files "${raymap_embedded_files}" PARENT_SCOPE)
endfunction()

raymap_flatten("${ROOT}/${INPUT}" text)
# Raw string with a delimiter that kernel code never contains.
file(WRITE "${OUTPUT}.tmp" "// Generated from ${INPUT} by cmake/EmbedKernel.cmake. Do not edit.\n"
  "namespace raymap::kernels {\nextern const char* const ${SYMBOL};\n"
  "const char* const ${SYMBOL} = R\"raymap_kernel(${text})raymap_kernel\";\n}  // namespace raymap::kernels\n")
file(COPY_FILE "${OUTPUT}.tmp" "${OUTPUT}" ONLY_IF_DIFFERENT)
file(REMOVE "${OUTPUT}.tmp")
