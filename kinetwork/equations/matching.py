"""Maximum matchings of equations to unknowns (structural analysis), the same in every run.

networkx's Hopcroft-Karp walks sets of nodes; with nodes such as ``("e", 3)`` their order
follows the hash of the string, which Python salts per process, so one model could name
different equations or unknowns from one run to the next in its refusals. Here the nodes are
integers (rows 0..m-1, unknowns m..m+n-1), whose hashes are their values in every process.
"""

import networkx as nx


def maximum_matching(n_rows, n_cols, edges):
    """{row: column} of a maximum matching of rows to columns along ``edges`` ((row, column)
    pairs); rows left unmatched are absent."""
    g = nx.Graph()
    g.add_nodes_from(range(n_rows + n_cols))
    g.add_edges_from((int(i), n_rows + int(j)) for i, j in edges)
    found = nx.bipartite.hopcroft_karp_matching(g, top_nodes=range(n_rows))
    return {i: found[i] - n_rows for i in range(n_rows) if i in found}
