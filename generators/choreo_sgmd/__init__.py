"""SGMD: style-guided motion diffusion (Wang et al.), the `choreo generate` backend.

Placeholder until the SGMD generator issue lands: it registers itself so `choreo generators`
shows it, and says plainly that it cannot generate yet.
"""

from choreo.generator import GeneratorPlugin

plugin = GeneratorPlugin(
    name="sgmd",
    summary="style-guided transformer motion diffusion (choreo generate / inbetween / inpaint / trajectory)",
    ready=False,
    status="placeholder: model, training and default weights not implemented yet (SGMD generator issue)",
)
