//! 1D convolutional residual encoder/decoder with temporal down/up-sampling (T2M-GPT/MoMask).
