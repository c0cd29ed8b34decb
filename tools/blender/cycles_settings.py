# SPDX-License-Identifier: MIT OR Apache-2.0
"""The Cycles settings every comparison with aperture starts from."""


def unbiased(sc, spp, seed):
    """Sets scene `sc` to render with Cycles on the CPU as aperture does: `spp` samples of a fixed
    `seed`, a one-pixel box filter, no adaptive sampling, denoising, clamping or glossy blur, and
    unbiased paths of up to 12 bounces of any kind, as aperture's default --max-bounces 12
    (Cycles' defaults stop diffuse paths after 4 bounces and cull dim lights). 32-bit EXR out."""
    sc.render.engine = "CYCLES"
    cy = sc.cycles
    cy.device = "CPU"
    cy.samples = spp
    cy.use_adaptive_sampling = False
    cy.use_denoising = False
    cy.sample_clamp_direct = 0.0
    cy.sample_clamp_indirect = 0.0
    cy.pixel_filter_type = "BOX"
    cy.filter_width = 1.0
    cy.seed = seed
    cy.use_animated_seed = False
    cy.blur_glossy = 0.0
    cy.caustics_reflective = True
    cy.caustics_refractive = True
    cy.max_bounces = 12
    cy.diffuse_bounces = 12
    cy.glossy_bounces = 12
    cy.transmission_bounces = 12
    cy.light_sampling_threshold = 0.0
    sc.render.film_transparent = False
    sc.render.image_settings.file_format = "OPEN_EXR"
    sc.render.image_settings.color_depth = "32"
