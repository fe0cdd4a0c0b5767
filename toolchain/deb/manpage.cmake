# A man page from a program's own help: cmake -DPROGRAM=path -DNAME=qnavd -DVERSION=0.1.0
#   [-DEMULATOR=qemu-aarch64;-L;...] -DOUT=qnavd.1.gz -P manpage.cmake
# Runs `PROGRAM --help` (its stdout; its stderr only when stdout is empty, as with a usage text on
# stderr; sanitizer builds run with leak checks off so no report lands in the page) and writes a roff page
# (NAME, SYNOPSIS/DESCRIPTION as the help text verbatim, FILES, SEE ALSO), gzip-compressed as Debian
# ships man pages. Fails when the program prints nothing.
foreach(v PROGRAM NAME VERSION OUT)
  if(NOT DEFINED ${v})
    message(FATAL_ERROR "manpage.cmake: -D${v}= missing")
  endif()
endforeach()
set(ENV{ASAN_OPTIONS} "detect_leaks=0")
execute_process(COMMAND ${EMULATOR} ${PROGRAM} --help
  OUTPUT_VARIABLE help ERROR_VARIABLE help_err RESULT_VARIABLE rc TIMEOUT 30)
string(STRIP "${help}" help)
if(help STREQUAL "")
  string(STRIP "${help_err}" help)
endif()
if(help STREQUAL "")
  message(FATAL_ERROR "manpage.cmake: '${PROGRAM} --help' printed nothing (exit ${rc})")
endif()
# roff: a leading '.' or "'" would be a request, a backslash an escape.
string(REPLACE "\\" "\\e" help "${help}")
string(REGEX REPLACE "(^|\n)([.'])" "\\1\\\\&\\2" help "${help}")
if(NAME STREQUAL "qnavd")
  set(summary "qnav navigation daemon (route teach and repeat, visual odometry) for AUVs and rovers")
  set(files ".TP\n/etc/qnav/qnavd.toml\nthe configuration the service reads (a conffile)\n.TP\n/usr/share/qnav/examples/\nexample configurations: vehicle.toml (real buses), sim.toml (simulated vehicle)\n.TP\n/var/lib/qnav/routes/\ntaught routes (route_<id>.qroute)\n.TP\n/usr/lib/systemd/system/qnavd.service\nthe systemd unit\n.TP\n/usr/share/qnav/qnav.dbc\nthe CAN messages qnavd reads and sends\n")
  set(see "qnav(1), systemctl(1), /usr/share/doc/qnav/qnavd.md, /usr/share/doc/qnav/configuration.md")
else()
  set(summary "the qnav engineers' tool: train, replay, evaluate, plot and simulate over recorded files")
  set(files ".TP\n/usr/share/qnav/qnav.dbc\nthe CAN interface (qnav can dbc)\n")
  set(see "qnavd(1), /usr/share/doc/qnav/README.md")
endif()
string(TOUPPER "${NAME}" upper)
file(WRITE ${OUT}.roff
".TH ${upper} 1 \"\" \"qnav ${VERSION}\" \"User Commands\"
.SH NAME
${NAME} \\- ${summary}
.SH SYNOPSIS AND OPTIONS
The text of \\fB${NAME} --help\\fR:
.PP
.nf
${help}
.fi
.SH FILES
${files}.SH SEE ALSO
${see}
")
file(ARCHIVE_CREATE OUTPUT ${OUT} PATHS ${OUT}.roff FORMAT raw COMPRESSION GZip)
file(REMOVE ${OUT}.roff)
