// Sorts a singly linked list in place, relinking its nodes: bottom-up merge
// sort, O(n log n) steps, no extra memory, stable. Shared by the VOIT resolve
// (long fragment lists) and the pick resolve. The includer defines:
//   LIST_NEXT(i)       the next link of node i (an lvalue)
//   LIST_BEFORE(a, b)  whether node a sorts before node b
//   LIST_END           the end marker
// A selection walk would take n^2 steps, and llvmpipe stops any shader after
// 65535 loop iterations in all (LP_MAX_TGSI_LOOP_ITERATIONS): this keeps
// about 2500 nodes per list within it; a GPU has no such limit.
uint list_sort(uint head) {
    uint list = head;
    for (uint width = 1u;; width *= 2u) {
        uint p = list, tail = LIST_END, merges = 0u;
        list = LIST_END;
        while (p != LIST_END) {
            ++merges;
            uint q = p, psize = 0u;
            for (uint i = 0u; i < width && q != LIST_END; ++i) {
                ++psize;
                q = LIST_NEXT(q);
            }
            uint qsize = width;
            while (psize > 0u || (qsize > 0u && q != LIST_END)) {
                uint e;
                bool take_q = psize == 0u || (qsize > 0u && q != LIST_END && LIST_BEFORE(q, p));
                if (take_q) {
                    e = q;
                    q = LIST_NEXT(q);
                    --qsize;
                } else {
                    e = p;
                    p = LIST_NEXT(p);
                    --psize;
                }
                if (tail == LIST_END)
                    list = e;
                else
                    LIST_NEXT(tail) = e;
                tail = e;
            }
            p = q;
        }
        if (tail != LIST_END) LIST_NEXT(tail) = LIST_END;
        if (merges <= 1u) break;
    }
    return list;
}
