# Writes the manual page OUT (gzip-compressed) from the tool's own help:
# help2man over `isoscope --help` and `--version`, and a COMMANDS section that
# holds each subcommand's `--help` as the tool prints it. So the page says what
# the program says, and changes when its options do.
#   cmake -DEXE=<isoscope> -DVERSION=<x.y.z> -DOUT=<isoscope.1.gz> -DHELP2MAN=<help2man> -DGZIP=<gzip> -P man.cmake
get_filename_component(dir "${EXE}" DIRECTORY)
get_filename_component(out_dir "${OUT}" DIRECTORY)
set(ENV{PATH} "${dir}:$ENV{PATH}") # run as "isoscope", so its help says "Usage: isoscope ..."
execute_process(COMMAND isoscope --help OUTPUT_VARIABLE top RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "isoscope --help failed (${rc})")
endif()
# The subcommands: the lines after "Subcommands:", their first word.
string(REGEX REPLACE ".*\nSubcommands:\n" "" listing "${top}")
string(REGEX MATCHALL "\n?  [a-z]+ " names "${listing}")
set(include "[DESCRIPTION]\nisoscope loads CT volumes and meshes (NIfTI, NRRD, MetaImage, VTI, OpenVDB, DICOM folders; STL, PLY, OBJ, VTP) in patient coordinates (LPS millimetres), extracts isosurfaces, renders them headless through OpenGL 4.5, measures, and exports annotated figures; \\fBisoscope gui\\fR opens the desktop app.\n\n[COMMANDS]\n")
foreach(n ${names})
  string(STRIP "${n}" n)
  execute_process(COMMAND isoscope ${n} --help OUTPUT_VARIABLE help RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "isoscope ${n} --help failed (${rc})")
  endif()
  # roff: backslashes doubled, a line starting with . or ' escaped.
  string(REPLACE "\\" "\\\\" help "${help}")
  string(REGEX REPLACE "\n([.'])" "\n\\\\&\\1" help "\n${help}")
  string(APPEND include ".SS ${n}\n.nf${help}.fi\n")
endforeach()
string(APPEND include "\n[SEE ALSO]\nThe documentation in /usr/share/doc/isoscope and the project's docs/ folder.\n")
file(WRITE "${out_dir}/isoscope.h2m" "${include}")
execute_process(COMMAND "${HELP2MAN}" --no-info --section 1 --source "isoscope ${VERSION}" --version-string "${VERSION}"
                        --name "inspect CT volumes, reconstruct and render isosurfaces"
                        --include "${out_dir}/isoscope.h2m" --output "${out_dir}/isoscope.1" isoscope
                RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "help2man failed (${rc})")
endif()
execute_process(COMMAND "${GZIP}" -9nf "${out_dir}/isoscope.1" RESULT_VARIABLE rc)
if(NOT rc EQUAL 0)
  message(FATAL_ERROR "gzip failed (${rc})")
endif()
