#!/bin/sh
# Fails when the freestanding image is not plain SPARC V8 (+ the LEON3 extensions: casa, umac/smac):
#  1. ELF machine must be EM_SPARC (2) with no 32PLUS flags (the linker marks V8+ objects EM_SPARC32PLUS);
#  2. no V9-only instruction or register in the disassembly (64-bit loads/stores/shifts/multiply/divide,
#     conditional moves, register branches, predicted branches with %icc/%xcc, popc, casx, V9 privileged
#     registers, ...). Every object is also assembled with -Aleon, which rejects V9 opcodes outright.
# usage: check-no-v9.sh OBJDUMP READELF ELF
set -u
objdump=$1 readelf=$2 elf=$3
machine=$("$readelf" -h "$elf" | sed -n 's/^ *Machine: *//p')
flags=$("$readelf" -h "$elf" | sed -n 's/^ *Flags: *//p')
if [ "$machine" != "Sparc" ] || [ "$flags" != "0x0" ]; then
  echo "FAIL: $elf is '$machine' flags '$flags' (want plain Sparc, flags 0x0: no V8+)"; exit 1
fi
v9=$("$objdump" -d --no-show-raw-insn "$elf" | awk -F'\t' 'NF >= 2 { print $2 "\t" $3 }' |
  grep -E '^(ldx|ldxa|stx|stxa|ldsw|ldswa|casx|casxa|sllx|srlx|srax|mulx|sdivx|udivx|popc|flushw|return|saved|restored|done|retry|rdpr|wrpr|prefetcha?|mov(a|n|ne|e|g|le|ge|l|gu|leu|cc|cs|pos|neg|vc|vs|nz|z|geu|lu|u|ug|ul|lg|ue|uge|ule|o)(,pn|,pt)?|movr[a-z]*|fmov[sdq](a|n|ne|e|g|le|ge|l|gu|leu|cc|cs|pos|neg|vc|vs|nz|z|u|ug|ul|lg|ue|uge|ule|o)|fmovr[a-z]*|br(z|lez|lz|nz|gz|gez)(,a)?(,pn|,pt)?|[a-z]+,(a,)?p[nt]|f[a-z]+q|ldqf|stqf|ldqfa|stqfa|sir|membar|stbar_v9|fxtos|fxtod|fxtoq|fstox|fdtox|fqtox)\b|%xcc|%fcc[123]|%asi\b|%ccr|%pstate|%tick|%fprs|%tstate|%canrestore|%cansave' || true)
if [ -n "$v9" ]; then
  echo "FAIL: V9-only instructions in $elf:"; echo "$v9" | sort | uniq -c | head -40; exit 1
fi
n=$("$objdump" -d "$elf" | grep -c '^ *[0-9a-f]*:')
echo "PASS: $elf is SPARC V8 (LEON3): $n instructions, no V9 opcode"
