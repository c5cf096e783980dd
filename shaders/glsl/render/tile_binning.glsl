// Conservative, opacity-aware tile binning shared by the projection (count) and emit passes so both
// enumerate exactly the same tiles. A Gaussian reaches a pixel iff opacity * exp(power) >= 1/255, i.e.
// q(d) = a dx^2 + 2 b dx dy + c dy^2 <= 2 ln(255 opacity) (conventions.md). A tile is kept when the
// minimum of q over the rectangle spanned by the tile's pixel centers is below that threshold plus a
// margin that covers the float32 rounding of the blend pass's own evaluation, so no pixel the blend
// pass would light is ever missed; extra tiles only cost time, never change the image.

// Threshold on q with its float32 margin. Returns a negative value when the Gaussian reaches nothing.
float binning_q_threshold(float opacity) {
    if (!(opacity >= ALPHA_MIN)) return -1.0;
    return 2.0 * log(255.0 * opacity) * 1.0001 + 1e-3;
}

// Quadratic form of the conic at offset (dx, dy) from the mean.
float conic_q(vec3 conic, float dx, float dy) {
    return conic.x * dx * dx + 2.0 * conic.y * dx * dy + conic.z * dy * dy;
}

// Minimum of q on the segment {x = fixed dx, dy in [y0, y1]}.
float min_q_on_vertical_edge(vec3 conic, float dx, float y0, float y1) {
    float dy = clamp(-conic.y * dx / conic.z, y0, y1);
    return conic_q(conic, dx, dy);
}

float min_q_on_horizontal_edge(vec3 conic, float dy, float x0, float x1) {
    float dx = clamp(-conic.y * dy / conic.x, x0, x1);
    return conic_q(conic, dx, dy);
}

// Does the ellipse q <= threshold touch the rectangle [x0,x1] x [y0,y1] (offsets from the mean)?
bool ellipse_touches_rect(vec3 conic, float threshold, float x0, float x1, float y0, float y1) {
    if (x0 <= 0.0 && 0.0 <= x1 && y0 <= 0.0 && 0.0 <= y1) return true;
    float q = min(min(min_q_on_vertical_edge(conic, x0, y0, y1), min_q_on_vertical_edge(conic, x1, y0, y1)),
                  min(min_q_on_horizontal_edge(conic, y0, x0, x1), min_q_on_horizontal_edge(conic, y1, x0, x1)));
    // float32 rounding of q in the blend pass grows with the size of its terms, not of q itself
    float mx = max(abs(x0), abs(x1));
    float my = max(abs(y0), abs(y1));
    float term_scale = abs(conic.x) * mx * mx + 2.0 * abs(conic.y) * mx * my + abs(conic.z) * my * my;
    return q <= threshold + 1e-5 * term_scale;
}

// A Gaussian's tile rectangle (x0, y0, x1, y1; exclusive ends) is walked row by row in one loop of
// rect_tiles(rect) steps, next_tile moving (tx, ty) on from (x0, y0): one loop, not one per row,
// because lavapipe runs a loop's body once more, masked, after its last iteration.
uint rect_tiles(uvec4 rect) {
    return (rect.z - rect.x) * (rect.w - rect.y);
}

void next_tile(uvec4 rect, inout uint tx, inout uint ty) {
    tx++;
    if (tx == rect.z) {
        tx = rect.x;
        ty++;
    }
}

// Does the Gaussian (mean xy, conic, threshold) touch tile (tx, ty) of a width x height image?
bool gaussian_touches_tile(vec2 xy, vec3 conic, float threshold, uint tx, uint ty, uint width, uint height) {
    float px0 = float(tx * TILE) + 0.5;
    float py0 = float(ty * TILE) + 0.5;
    float px1 = float(min(tx * TILE + TILE, width) - 1u) + 0.5;
    float py1 = float(min(ty * TILE + TILE, height) - 1u) + 0.5;
    return ellipse_touches_rect(conic, threshold, px0 - xy.x, px1 - xy.x, py0 - xy.y, py1 - xy.y);
}
