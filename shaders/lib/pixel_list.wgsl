// Pixels marked as bits, and the list of the marked pixels in row order: SMAA's edge pixels and
// MSAA's pixels shaded per sample. A pass that runs only on marked pixels runs over the list in
// a compact target (`lib/compact.wgsl`) instead of over the image: lavapipe shades 4×4 blocks
// of fragments as one, and most blocks with a marked pixel would carry idle lanes.
//
// The marks: two bits per pixel, sixteen pixels to a word, the image's rows one after the other
// (word y · row_words() + x / 16, bits 2·(x % 16) and 2·(x % 16) + 1); a pixel is marked when
// either of its bits is set. The includer writes them into `edge_words`, then runs
// `list_count_rows`, `list_scan_rows` (one invocation) and `list_emit`. Layout of the list
// buffer, in words: the length; each row's first index; each mark word's first index within
// its row; the entries (x | y << 16). The includer defines `fn pixel_marks(p: vec2<i32>) -> u32`,
// the two bits of pixel p, which `write_mark_word` packs.

// The image's size in pixels.
override WIDTH: u32 = 1u;
override HEIGHT: u32 = 1u;

// Written by the pass that marks and lists (the first two), read by the passes after it (the
// same buffers, under the second two names).
@group(2) @binding(1) var<storage, read_write> edge_words: array<u32>;
@group(2) @binding(2) var<storage, read_write> list_words: array<u32>;
@group(2) @binding(3) var<storage, read> edges: array<u32>;
@group(2) @binding(4) var<storage, read> list: array<u32>;

const SLOTS: u32 = 16u;
// Bit 0 of every slot.
const LOW_BITS: u32 = 0x55555555u;

const LIST_LENGTH: u32 = 0u;
const ROW_STARTS: u32 = 4u;

fn row_words() -> u32 {
    return (WIDTH + SLOTS - 1u) / SLOTS;
}

fn word_starts() -> u32 {
    return ROW_STARTS + HEIGHT;
}

fn entries() -> u32 {
    return word_starts() + HEIGHT * row_words();
}

// Bit 0 of each slot of a mark word: the pixel is marked.
fn edge_pixels(word: u32) -> u32 {
    return (word | (word >> 1u)) & LOW_BITS;
}

// Mark word `index`: sixteen pixels of a row, each slot the includer's `pixel_marks`.
fn write_mark_word(index: u32) {
    let words = row_words();
    if index >= HEIGHT * words {
        return;
    }
    let y = i32(index / words);
    let x0 = i32((index % words) * SLOTS);
    var word = 0u;
    for (var i = 0u; i < SLOTS; i++) {
        let x = x0 + i32(i);
        if x < i32(WIDTH) {
            word |= pixel_marks(vec2<i32>(x, y)) << (2u * i);
        }
    }
    edge_words[index] = word;
}

// Each mark word's first index within its row, and each row's length (in ROW_STARTS).
@compute @workgroup_size(64)
fn list_count_rows(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= HEIGHT {
        return;
    }
    let words = row_words();
    var count = 0u;
    for (var w = 0u; w < words; w++) {
        let index = id.x * words + w;
        list_words[word_starts() + index] = count;
        count += countOneBits(edge_pixels(edge_words[index]));
    }
    list_words[ROW_STARTS + id.x] = count;
}

// Row lengths to row starts, and the list's length.
@compute @workgroup_size(1)
fn list_scan_rows() {
    var total = 0u;
    for (var y = 0u; y < HEIGHT; y++) {
        let count = list_words[ROW_STARTS + y];
        list_words[ROW_STARTS + y] = total;
        total += count;
    }
    list_words[LIST_LENGTH] = total;
}

// The entries of one mark word.
@compute @workgroup_size(64)
fn list_emit(@builtin(global_invocation_id) id: vec3<u32>) {
    let words = row_words();
    if id.x >= HEIGHT * words {
        return;
    }
    let y = id.x / words;
    var pending = edge_pixels(edge_words[id.x]);
    var index = list_words[ROW_STARTS + y] + list_words[word_starts() + id.x];
    let x0 = (id.x % words) * SLOTS;
    while pending != 0u {
        list_words[entries() + index] = (x0 + firstTrailingBit(pending) / 2u) | (y << 16u);
        pending &= pending - 1u;
        index += 1u;
    }
}

// The pixel of list entry `index`.
fn listed_pixel(index: u32) -> vec2<i32> {
    let entry = list[entries() + index];
    return vec2<i32>(vec2<u32>(entry & 0xFFFFu, entry >> 16u));
}

// The list index of pixel `p`, or -1 where it is not marked.
fn list_index(p: vec2<u32>) -> i32 {
    let words = row_words();
    let word = edges[p.y * words + p.x / SLOTS];
    if ((word >> (2u * (p.x % SLOTS))) & 3u) == 0u {
        return -1;
    }
    let before = edge_pixels(word) & ((1u << (2u * (p.x % SLOTS))) - 1u);
    return i32(list[ROW_STARTS + p.y] + list[word_starts() + p.y * words + p.x / SLOTS] + countOneBits(before));
}
