"""ChoreoGraph: style-selected, beat-warped dynamic motion graph, the `choreo graph` backend.

Placeholder until the ChoreoGraph generator issue lands.
"""

from choreo.generator import GeneratorPlugin

plugin = GeneratorPlugin(
    name="graph",
    summary="style embeddings + tempo-density DTW + dynamic motion graph (choreo graph)",
    ready=False,
    status="placeholder: style/tempo models, repertoire and graph search not implemented yet (ChoreoGraph issue)",
)
