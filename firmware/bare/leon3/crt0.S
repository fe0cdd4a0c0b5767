/* crt0.S: bare-metal start-up for a LEON3 (SPARC V8) in supervisor mode, no OS, no libc.
 *
 *  - trap table (256 entries x 16 bytes, 4 KiB aligned): window overflow (tt 0x05) and underflow
 *    (tt 0x06) handlers, everything else goes to bad_trap (prints "TRAP tt=xx pc=... npc=..." on the
 *    UART, then shuts the machine down). No interrupts are used (PIL = 15).
 *  - _start: TBR, WIM, PSR (S, PS, EF = FPU on, ET = traps on), FSR, stack, .bss zeroing, C++
 *    constructors (.init_array), main(), then shutdown with main's return value.
 *  - bare_shutdown(code): disables traps (PSR.ET = 0) and executes `ta 0`. QEMU's LEON3 model has
 *    CPU_FEATURE_TA0_SHUTDOWN: a trap with ET = 0 that is `ta 0` powers the machine off cleanly
 *    (qemu exits 0); on a real LEON3 the CPU enters error mode and halts, which the debug unit sees.
 *    The exit code itself is printed by the C side before shutting down.
 *  Only SPARC V8 instructions are used (assembled with -Aleon by the cross gcc).
 */
#define NWINDOWS 8          /* checked at start-up against the WIM's implemented bits */
#define PSR_EF   0x00001000
#define PSR_PIL  0x00000f00
#define PSR_S    0x00000080
#define PSR_PS   0x00000040
#define PSR_ET   0x00000020

        .section ".text.traptable", "ax"
        .align  4096
        .global trap_table
trap_table:
/* Each entry: 4 instructions. %l1 = PC, %l2 = nPC of the trapped instruction (hardware). */
#define BAD_TRAP(n) mov n, %l3; sethi %hi(bad_trap), %l4; jmp %l4 + %lo(bad_trap); mov %psr, %l0;
#define TRAP_TO(h)  mov %psr, %l0; sethi %hi(h), %l4; jmp %l4 + %lo(h); nop;
        BAD_TRAP(0x00)  /* 0x00 reset: re-entry through the table is a fault here */
        BAD_TRAP(0x01)  /* instruction_access_exception */
        BAD_TRAP(0x02)  /* illegal_instruction (e.g. a V9 opcode) */
        BAD_TRAP(0x03)  /* privileged_instruction */
        BAD_TRAP(0x04)  /* fp_disabled */
        TRAP_TO(window_overflow)   /* 0x05 */
        TRAP_TO(window_underflow)  /* 0x06 */
        BAD_TRAP(0x07)  /* mem_address_not_aligned */
        BAD_TRAP(0x08)  /* fp_exception */
        BAD_TRAP(0x09)  /* data_access_exception */
        BAD_TRAP(0x0a)  /* tag_overflow */
        BAD_TRAP(0x0b)  /* watchpoint */
        .set    tnum, 0x0c
        .rept   256 - 0x0c
        BAD_TRAP(tnum)
        .set    tnum, tnum + 1
        .endr

        .text
        .align  4
/* Window overflow: the trap window is the invalid one; save the next window (the oldest in use)
 * to its stack and rotate the WIM right by one (classic SPARC V8 handler, as in RTEMS/BCC). */
window_overflow:
        mov     %wim, %l3
        mov     %g1, %l7
        srl     %l3, 1, %g1
        sll     %l3, NWINDOWS - 1, %l4
        or      %l4, %g1, %g1
        save                            /* into the window to be saved */
        mov     %g1, %wim
        nop; nop; nop
        std     %l0, [%sp + 0x00]
        std     %l2, [%sp + 0x08]
        std     %l4, [%sp + 0x10]
        std     %l6, [%sp + 0x18]
        std     %i0, [%sp + 0x20]
        std     %i2, [%sp + 0x28]
        std     %i4, [%sp + 0x30]
        std     %i6, [%sp + 0x38]
        restore                         /* back to the trap window */
        mov     %l7, %g1
        jmp     %l1                     /* re-execute the save */
        rett    %l2

/* Window underflow: restore the window two below the trap window from its stack, rotate the WIM
 * left by one. */
window_underflow:
        mov     %wim, %l3
        sll     %l3, 1, %l4
        srl     %l3, NWINDOWS - 1, %l5
        or      %l5, %l4, %l5
        mov     %l5, %wim
        nop; nop; nop
        restore
        restore                         /* into the window to restore */
        ldd     [%sp + 0x00], %l0
        ldd     [%sp + 0x08], %l2
        ldd     [%sp + 0x10], %l4
        ldd     [%sp + 0x18], %l6
        ldd     [%sp + 0x20], %i0
        ldd     [%sp + 0x28], %i2
        ldd     [%sp + 0x30], %i4
        ldd     [%sp + 0x38], %i6
        save
        save                            /* back to the trap window */
        jmp     %l1                     /* re-execute the restore */
        rett    %l2

/* Unexpected trap: %l3 = trap number, %l1/%l2 = PC/nPC. Traps are disabled (ET = 0) here, so the
 * report runs on a fresh stack in the trap window's locals/outs with plain calls only; the UART
 * print routines are leaf-safe C functions, but a window overflow inside them would be fatal, so
 * move to a known-good window first: set WIM = 0 (no invalid window; nothing is returned to). */
bad_trap:
        mov     %g0, %wim
        nop; nop; nop
        set     __trap_stack_top - 96, %sp
        mov     %l3, %o0
        mov     %l1, %o1
        call    bare_report_trap        /* void bare_report_trap(tt, pc, npc): prints, then shuts down */
        mov     %l2, %o2
        ba      bare_halt
        nop

        .global _start
_start:
        /* Supervisor, traps off while the machine state is set up, FPU on, interrupts masked. */
        set     PSR_S | PSR_PS | PSR_PIL | PSR_EF, %g1
        wr      %g1, %psr
        nop; nop; nop
        set     trap_table, %g1
        wr      %g1, %tbr
        /* Number of windows: write all ones to the WIM, read back the implemented bits. */
        mov     -1, %g1
        wr      %g1, %wim
        nop; nop; nop
        mov     %wim, %g2
        set     (1 << NWINDOWS) - 1, %g3
        cmp     %g2, %g3
        bne     bare_halt               /* built for NWINDOWS windows: anything else is unsupported */
        nop
        mov     2, %g1                  /* CWP = 0; window 1 invalid (nothing above _start) */
        wr      %g1, %wim
        nop; nop; nop
        /* Stack at the top of the stack region, 8-byte aligned, a minimum frame reserved. */
        set     __stack_top, %sp
        andn    %sp, 7, %sp
        sub     %sp, 96, %sp
        mov     %g0, %fp
        /* Zero .bss (word at a time; the linker script aligns both ends to 8). */
        set     __bss_start, %g1
        set     __bss_end, %g2
1:      cmp     %g1, %g2
        bgeu    2f
        nop
        st      %g0, [%g1]
        ba      1b
        add     %g1, 4, %g1
2:      /* FSR: round to nearest, no FP traps enabled. */
        set     fsr_init, %g1
        ld      [%g1], %fsr
        nop; nop; nop
        /* Traps on. */
        mov     %psr, %g1
        or      %g1, PSR_ET, %g1
        wr      %g1, %psr
        nop; nop; nop
        /* C++ constructors. */
        set     __init_array_start, %l0
        set     __init_array_end, %l1
3:      cmp     %l0, %l1
        bgeu    4f
        nop
        ld      [%l0], %g1
        call    %g1
        nop
        ba      3b
        add     %l0, 4, %l0
4:      call    bare_main_entry         /* int bare_main_entry(void): runs main, prints the code */
        nop
        call    bare_shutdown
        nop

/* void bare_shutdown(int): power off (QEMU: TA0_SHUTDOWN with traps disabled). */
        .global bare_shutdown
bare_shutdown:
        mov     %psr, %g1
        andn    %g1, PSR_ET, %g1
        wr      %g1, %psr
        nop; nop; nop
        ta      0
        /* fall through on hardware without the shutdown feature */
        .global bare_halt
bare_halt:
        ba      bare_halt
        nop

        .section ".rodata"
        .align  4
fsr_init:
        .word   0
        .section .note.GNU-stack,"",@progbits
