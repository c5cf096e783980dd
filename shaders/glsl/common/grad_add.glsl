// Float accumulation into gradient buffers (`GradBuf`): float atomic adds, or, with NO_FLOAT_ATOMICS
// (the *_cas shader variants, for devices without VK_EXT_shader_atomic_float), a compare-and-swap loop
// over the bits. The including shader enables GL_EXT_shader_atomic_float unless NO_FLOAT_ATOMICS.
#ifdef NO_FLOAT_ATOMICS
#define GradBuf Uints
#else
#define GradBuf Floats
#endif

void grad_add(GradBuf buf, uint index, float value) {
#ifdef NO_FLOAT_ATOMICS
    uint old = buf.v[index];
    for (;;) {
        uint desired = floatBitsToUint(uintBitsToFloat(old) + value);
        uint seen = atomicCompSwap(buf.v[index], old, desired);
        if (seen == old) break;
        old = seen;
    }
#else
    atomicAdd(buf.v[index], value);
#endif
}

float grad_read(GradBuf buf, uint index) {
#ifdef NO_FLOAT_ATOMICS
    return uintBitsToFloat(buf.v[index]);
#else
    return buf.v[index];
#endif
}
