"""The smoothers written straight from the paper, one vertex at a time, in plain Python floats.

Deliberately naive: the vectorized core must agree with these loops to rounding.
"""


def adjacency(n, edges):
    adj = [set() for _ in range(n)]
    for a, b in edges:
        a, b = int(a), int(b)
        if a != b:
            adj[a].add(b)
            adj[b].add(a)
    return adj


def _mean(points):
    points = list(points)
    return [sum(p[k] for p in points) / len(points) for k in range(3)]


def smooth_loop(
    positions,
    edges,
    *,
    method,
    alpha=0.0,
    beta=0.5,
    iterations,
    mode="simultaneous",
    fixed=(),
    max_deviation=0.0,
    adj=None,
):
    """``adj``: a list of neighbour sets, one per vertex, used instead of the one ``edges`` give (a
    directed adjacency: j in adj[i] without i in adj[j]). ``max_deviation``: the deviation limit, a
    projection onto the ball around each input position after every iteration (0: none)."""
    n = len(positions)
    adj = adjacency(n, edges) if adj is None else [set(int(j) for j in a) for a in adj]
    fixed = set(int(i) for i in fixed) | {i for i in range(n) if not adj[i]}  # section 2
    o = [[float(c) for c in p] for p in positions]
    p = [list(v) for v in o]
    sequential = mode == "sequential"
    for _ in range(iterations):
        q = [list(v) for v in p]
        # The Laplacian pass. Sequential: neighbours' positions already updated in this pass.
        new = [list(v) for v in q]
        for i in range(n):
            if i in fixed:
                continue
            source = new if sequential else q
            avg = _mean(source[j] for j in adj[i])
            if method in ("plain", "hc"):
                new[i] = avg
            elif method == "central":  # 3.2
                new[i] = [alpha * q[i][k] + (1 - alpha) * avg[k] for k in range(3)]
            elif method == "original":  # 3.3
                new[i] = [alpha * o[i][k] + (1 - alpha) * avg[k] for k in range(3)]
        if method == "hc":  # Algorithm 1, second loop
            b = {
                i: [new[i][k] - (alpha * o[i][k] + (1 - alpha) * q[i][k]) for k in range(3)]
                for i in range(n)
                if i not in fixed
            }
            zero = [0.0, 0.0, 0.0]
            corrected = [list(v) for v in new]
            for i in range(n):
                if i in fixed:
                    continue
                m = len(adj[i])
                sum_b = [sum(b.get(j, zero)[k] for j in adj[i]) for k in range(3)]
                corrected[i] = [new[i][k] - (beta * b[i][k] + (1 - beta) / m * sum_b[k]) for k in range(3)]
            new = corrected
        if max_deviation > 0.0:  # the deviation limit: back onto the ball around the input position
            for i in range(n):
                away = [new[i][k] - o[i][k] for k in range(3)]
                length = sum(c * c for c in away) ** 0.5
                if length > max_deviation:
                    new[i] = [o[i][k] + away[k] * (max_deviation / length) for k in range(3)]
        p = new
    return p
