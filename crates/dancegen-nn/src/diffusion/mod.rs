//! Diffusion: schedules, DDPM/DDIM sampling with classifier-free guidance, inpainting, PDDM, long-form sampling.
